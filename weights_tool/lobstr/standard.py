"""The standard skeleton: the skeleton of the training data (Bandai Namco Research Motion Dataset
character, 21 joints from Hips; joint_Root dropped), offsets in metres, Y up, facing +Z.
The network's outputs are local rotations of its 8 lower-body joints (skeleton.LOWER); the weights
file carries this table in meta.skeleton so the C++ side needs no copy of it.
"""
STANDARD = {
    "names": ["Hips", "Spine", "Chest", "Neck", "Head", "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L",
              "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R", "UpperLeg_L", "LowerLeg_L", "Foot_L",
              "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"],
    "parents": [-1, 0, 1, 2, 3, 2, 5, 6, 7, 2, 9, 10, 11, 0, 13, 14, 15, 0, 17, 18, 19],
    "offsets": [[0.0, 0.0, 0.0], [0.157357, 0.0, 0.0], [0.089846, -0.004062, 0.0], [0.163773, 0.0, 0.0],
                [0.064567, 0.0, 0.0], [0.129942, -0.002427, 0.049804], [0.053481, 0.0, 0.0],
                [0.243286, 0.0, 0.0], [0.222916, 0.0, 0.0], [0.129945, -0.002427, -0.049804],
                [-0.053481, 0.0, 0.0], [-0.243289, 3e-06, 0.0], [-0.222915, -1e-06, 0.0],
                [-0.021925, -0.064694, 0.0], [0.390811, 0.0, 0.0], [0.409854, 0.0, 0.0], [0.117543, 0.0, 0.0],
                [-0.021925, 0.064694, 0.0], [-0.390811, -2.3e-05, -0.000402], [-0.409854, 0.0, 0.0],
                [-0.117543, 0.0, 0.0]],
    # median standing heights above the floor over the training clips' first frames (metres)
    "standing_hips_height": 0.908,
    "standing_head_height": 1.378,
    # standing height of the toe-base joint above the floor (metres)
    "toe_height": 0.042,
}
