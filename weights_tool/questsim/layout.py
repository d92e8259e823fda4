"""Observation layout, mirror of QuestSimLayout in include/sparsebody/control/questsim_observation.hpp.

[o_sim,q (NJ) | o_sim,qd (NJ) | link positions (3 NB) | link 6D (6 NB) | link linear velocity (3 NB) |
 link angular velocity (3 NB) | foot forces L, R (6) | user frames t..t+NF, 27 each | height (1)]
"""

USER_FRAME = 27  # headset, left, right: position (3) + first two rotation columns (6)


def layout(bodies, joint_dofs, future=6):
    """Offsets of every block and the total size."""
    o = {}
    o["q"] = 0
    o["qd"] = o["q"] + joint_dofs
    o["x"] = o["qd"] + joint_dofs
    o["R"] = o["x"] + 3 * bodies
    o["xd"] = o["R"] + 6 * bodies
    o["w"] = o["xd"] + 3 * bodies
    o["f"] = o["w"] + 3 * bodies
    o["user"] = o["f"] + 6
    o["height"] = o["user"] + USER_FRAME * (future + 1)
    o["size"] = o["height"] + 1
    return o


def size(bodies, joint_dofs, future=6):
    return layout(bodies, joint_dofs, future)["size"]
