"""LoBSTr Python side: BVH loader, rotations, tracker synthesis, features, losses, a short training
run on a tiny synthetic batch, export, and the committed parity golden. No Bandai data needed."""
import json
import os

import numpy as np
import pytest
import torch

from weights_tool.format import read_weights
from weights_tool.lobstr import bvh, features, reference, rotations, skeleton, train
from weights_tool.lobstr.export import pipeline_meta
from weights_tool.lobstr.standard import STANDARD
from weights_tool.nets import LoBSTrNet

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
GOLDEN = os.path.join(ROOT, "tests", "pipeline", "golden")
CMU = "/usr/share/assimp/models/BVH/01_01.bvh"


def standard_bvh_text(frames=40, seed=0):
    """A BVH of the standard skeleton (cm, 6-channel joints like the training data) walking forward
    with swinging legs: synthetic motion for the tests."""
    rng = np.random.default_rng(seed)
    names, parents, offs = STANDARD["names"], STANDARD["parents"], STANDARD["offsets"]
    lines, depth = ["HIERARCHY"], {}
    for j, n in enumerate(names):
        p = parents[j]
        depth[j] = 0 if p < 0 else depth[p] + 1
        ind = "  " * depth[j]
        o = np.array(offs[j]) * 100
        lines += [f"{ind}{'ROOT' if p < 0 else 'JOINT'} {n}", ind + "{", f"{ind}  OFFSET {o[0]} {o[1]} {o[2]}",
                  f"{ind}  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
        if j + 1 == len(names) or parents[j + 1] != j:
            lines += [ind + "  End Site", ind + "  {", ind + "    OFFSET 0 0 0", ind + "  }"]
        nxt = parents[j + 1] if j + 1 < len(names) else -1
        a = j
        while a >= 0 and a != nxt:
            lines.append("  " * depth[a] + "}")
            a = parents[a]
    lines += ["MOTION", f"Frames: {frames}", "Frame Time: 0.0333333"]
    for f in range(frames):
        row = []
        for j, n in enumerate(names):
            pos = np.array(offs[j]) * 100
            rot = np.zeros(3)  # Z X Y degrees
            if j == 0:
                pos = np.array([0.0, 90.0, 1.0 * f])
                rot = np.array([90.0, 0.0, 0.0])  # the hips' X (spine) up, facing +Z
            if n.startswith("UpperLeg"):
                rot = np.array([180.0 if n.endswith("L") else 0.0, 0, 0]) + np.array([0, 0, 20 * np.sin(f / 4.0 + (n[-1] == "R") * np.pi)])
            rot = rot + rng.normal(0, 0.5, 3)
            row += list(pos) + list(rot)
        lines.append(" ".join(f"{v:.5f}" for v in row))
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def clip():
    return skeleton.Clip(bvh.parse(standard_bvh_text(), "synthetic.bvh"))


def test_bvh_parse_and_errors():
    b = bvh.parse(standard_bvh_text(5), "x.bvh")
    assert b.names == STANDARD["names"] and b.frames == 5 and b.motion.shape == (5, 21 * 6)
    with pytest.raises(bvh.BVHError, match="x.bvh:4: expected OFFSET"):
        bvh.parse(standard_bvh_text(5).replace("OFFSET 0.0 0.0 0.0", "OFFSET 0 0", 1), "x.bvh")
    with pytest.raises(bvh.BVHError, match="expected 126 values per frame"):
        bvh.parse(standard_bvh_text(5).rstrip("\n") + " 1\n", "x.bvh")


def test_rotations_roundtrip():
    rng = np.random.default_rng(0)
    R = rotations.random_rotations(rng, 100, 180.0)
    assert np.allclose(rotations.from6d(rotations.to6d(R)), R, atol=1e-9)
    assert np.allclose(rotations.quat_to_matrix(rotations.matrix_to_quat(R)), R, atol=1e-9)
    assert np.allclose(rotations.angle_between(R, R), 0, atol=1e-5)


def test_synthesis_and_features(clip):
    P, Q = clip.trackers()
    assert P.shape == (clip.frames, 4, 3) and np.isfinite(Q).all()
    # at the first frame the head and hand trackers are the facing frame (calibration convention)
    assert np.allclose(Q[0, 0], Q[0, 1], atol=1e-9) and np.allclose(Q[0, 0, :, 1], [0, 1, 0], atol=1e-9)
    X = features.features(P, Q, 1.0)
    assert X.shape == (clip.frames, 37)
    assert np.allclose(X[0, [0, 1, 2, 9, 10, 11]], 0)  # no velocity at the first frame
    # moving 1 cm per frame along world Z: the reference velocity is horizontal with that length
    assert np.allclose(np.linalg.norm(X[5, 0:3]), 0.01, atol=1e-6) and X[5, 1] == 0.0
    assert np.allclose(X[:, 36], P[:, 3, 1])
    # yaw invariance: rotating the whole scene about Y leaves the features unchanged
    Ry = rotations.axis_angle((0.0, 1.0, 0.0), 70.0)
    X2 = features.features(P @ Ry.T, Ry @ Q, 1.0)
    assert np.allclose(X, X2, atol=1e-9)


def test_noise_and_contacts(clip):
    rng = np.random.default_rng(0)
    P, Q = clip.trackers()
    Pn, Qn = skeleton.add_tracker_noise(rng, P, Q)
    d = np.linalg.norm(Pn - P, axis=-1)
    assert 0.003 < d.mean() < 0.02
    ang = rotations.angle_between(Qn, Q)
    assert ang.max() <= 1.5 + 1e-6 and ang.mean() > 0.1
    toes = [clip.roles["toe_l"], clip.roles["toe_r"]]
    floor = clip.pw[:, toes, 1].min() - 0.042 * clip.leg / 0.80  # the lowest toe touches the floor
    # the synthetic legs swing with no stance phase (toes mostly > 0.5 m/s): looser thresholds than the
    # data's give a mix of contact and swing frames
    C = skeleton.contact_labels(clip, floor, height=0.03, speed=2.0)
    assert C.shape == (clip.frames, 2) and 0 < C.mean() < 1
    assert skeleton.contact_labels(clip, floor, height=0.03, speed=0.3).sum() < C.sum()  # the speed test bites


def test_training_step_reduces_loss():
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    X = rng.normal(size=(4 * 40, 37)).astype(np.float32)
    Y = np.tile(rotations.to6d(np.eye(3)), 8)[None].repeat(160, 0).astype(np.float32)
    Y += rng.normal(0, 0.05, Y.shape).astype(np.float32)
    C = (rng.random((160, 2)) < 0.5).astype(np.int64)
    lens, starts = np.array([40] * 4), np.arange(4) * 40
    model = LoBSTrNet(hidden=16, latent=8)
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    fk = train.ToeFK()
    losses = []
    for it in range(80):
        xb, yb, cb, mb = train.padded(X, Y, C, lens, starts, np.arange(4), 16, rng)
        out, _ = model(xb, logits=True)
        loss, parts = train.losses(out, yb, cb, mb, fk)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.item())
    assert set(parts) == {"pose", "fk", "vel", "ce"}
    assert np.mean(losses[-5:]) < 0.6 * np.mean(losses[:5])


def test_toe_fk_matches_numpy_fk(clip):
    idx = [clip.bvh.index(n) for n in skeleton.LOWER]
    y = torch.from_numpy(rotations.to6d(clip.R_local[:, idx]).reshape(clip.frames, 48).astype(np.float32))
    toes = train.ToeFK()(y).numpy()
    hips = clip.roles["hips"]
    for s, role in enumerate(("toe_l", "toe_r")):
        local = np.einsum("fji,fj->fi", clip.Rw[:, hips], clip.pw[:, clip.roles[role]] - clip.pw[:, hips])
        assert np.allclose(toes[:, s], local, atol=1e-5)


def test_export_meta_is_what_cpp_reads(tmp_path):
    m = pipeline_meta(256, 128)
    assert m["rotation"] == {"representation": "6d", "layout": "columns", "columns": [2, 1]}
    assert m["lower_body_joints"] == skeleton.LOWER and len(m["skeleton"]["names"]) == 21
    assert "CC BY-NC 4.0" in m["credit"] and "non-commercial" in m["non_commercial"]


def test_committed_golden_reproduces():
    """The committed golden equals what the reference pipeline computes now (weights from the file)."""
    g = json.load(open(os.path.join(GOLDEN, "lobstr_pipeline_small.golden.json")))
    doc, tensors, norm = read_weights(os.path.join(GOLDEN, "lobstr_pipeline_small.weights.json"))
    model = LoBSTrNet(hidden=32, latent=16)
    model.load_state_dict({k: torch.tensor(v, dtype=torch.float32) for k, v in tensors.items()})
    pos = np.array(g["positions"], np.float32)
    quat = np.array(g["quaternions_xyzw"], np.float32)
    X, ys, yw = reference.run(model, norm["input_mean"].astype(np.float32), norm["input_std"].astype(np.float32),
                              pos, quat, g["scale"], g["window"])
    assert np.abs(X - np.array(g["features"])).max() < 1e-9
    assert np.abs(ys - np.array(g["outputs"])).max() < 1e-5
    assert np.abs(yw - np.array(g["window_outputs"])).max() < 1e-5
    if os.path.exists(CMU):  # the golden's trackers are the synthesis of the CMU clip
        c = skeleton.Clip(CMU)
        p2, q2, _ = reference.clip_ticks(c, 30.0, 0, len(pos))
        assert np.abs(p2 - pos).max() < 1e-6
        assert np.abs(reference.clip_scale(c) - g["scale"]) < 1e-12


def test_joint_roles_of_common_rigs():
    """map_roles, the twin of pose/joint_map.hpp, on the rigs of tests/pipeline/rig_names.json (the
    C++ test reads the same file)."""
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    with open(os.path.join(root, "tests", "pipeline", "rig_names.json")) as f:
        d = json.load(f)
    assert len(d["rigs"]) >= 12
    for r in d["rigs"]:
        m = skeleton.map_roles(r["names"])
        got = {role: (r["names"][m[role]] if role in m else None) for role in skeleton.ROLE_NAMES}
        assert got == r["roles"], r["rig"]
    assert skeleton.norm_name("mixamorig:LeftUpLeg") == "leftupleg"
    assert skeleton.norm_name("Bip01 L Thigh") == "lthigh"
    assert skeleton.norm_name("Bip01") == "bip01"
    for r in d["unmappable"]:
        with pytest.raises(ValueError, match="no joint for " + ", ".join(r["missing"])):
            skeleton.map_roles(r["names"])


def write_z_up(src, dst):
    """The BVH clip src (root channels X/Y/Z position, Z/Y/X rotation) written to dst with its world
    turned +Y -> +Z (a Z-up export, as AMASS / Blender write them); returns the turn."""
    b = bvh.load(src)
    assert [c.lower() for c in b.channels[0]] == ["xposition", "yposition", "zposition", "zrotation", "yrotation", "xrotation"]
    ax = rotations.axis_angle
    T = ax(rotations.AXES["X"], 90.0)  # +Y -> +Z
    m = b.motion.copy()
    for f in range(b.frames):
        z, y, x = m[f, 3:6]
        R = T @ ax(rotations.AXES["Z"], z) @ ax(rotations.AXES["Y"], y) @ ax(rotations.AXES["X"], x)
        m[f, :3] = T @ m[f, :3]
        m[f, 3:6] = np.degrees([np.arctan2(R[1, 0], R[0, 0]), np.arcsin(-R[2, 0]), np.arctan2(R[2, 1], R[2, 2])])
    lines = open(src).read().splitlines()
    k = next(i for i, l in enumerate(lines) if l.strip().startswith("Frame Time"))
    with open(dst, "w") as f:
        f.write("\n".join(lines[:k + 1]) + "\n" + "\n".join(" ".join(repr(float(v)) for v in row) for row in m) + "\n")
    return T


def test_z_up_clip_reads_as_y_up(tmp_path):
    """skeleton.up_axis_turn, the twin of recordings/bvh_up_axis.hpp (tests/pipeline/test_bvh_up_axis.cpp):
    the CMU clip 01_01 written with a Z-up world reads back with the original's world positions."""
    src = "/usr/share/assimp/models/BVH/01_01.bvh"  # assimp-testmodels, installed by .ci
    dst = tmp_path / "z_up.bvh"
    T = write_z_up(src, str(dst))
    a, z = skeleton.Clip(src), skeleton.Clip(str(dst))
    assert a.up_turn is None and z.up_turn is not None
    assert np.allclose(z.up_turn @ T, np.eye(3), atol=1e-12)
    assert np.abs(a.pw - z.pw).max() < 1e-9


def rig_text(uy, uz):
    """The rig of tests/pipeline/test_hips_point.cpp: centimetres, leg 40 + 40, thigh roots at
    (+-8, uy, uz) from the root; frame 1 moved by (10, 0, 5) cm and turned a quarter about Y."""
    end = "End Site\n{\nOFFSET 0 5 0\n}\n"

    def joint(name, x, y, z, inner):
        return f"JOINT {name}\n{{\nOFFSET {x} {y} {z}\nCHANNELS 3 Zrotation Xrotation Yrotation\n{inner}}}\n"

    def leg(side):
        s = "Left" if side > 0 else "Right"
        return joint(f"{s}UpLeg", 8.0 * side, uy, uz, joint(f"{s}Leg", 0, -40, 0, joint(
            f"{s}Foot", 0, -40, 0, joint(f"{s}ToeBase", 0, -4, 10, end))))
    text = ("HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
            + joint("Spine", 0, 16, 0, joint("Head", 0, 40, 0, end) + joint("LeftHand", 20, 20, 0, end)
                    + joint("RightHand", -20, 20, 0, end))
            + leg(1) + leg(-1) + "}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n")
    for f in range(2):
        v = np.zeros(6 + 3 * 12)
        v[0], v[1], v[2], v[5] = 10.0 * f, 100.0, 5.0 * f, 90.0 * f
        text += " ".join(repr(float(x)) for x in v) + "\n"
    return text


def test_pelvis_tracker_at_the_standard_hips_joint():
    """C++ twin: tests/pipeline/test_hips_point.cpp. A rig rooted 10 cm above and 5 cm behind its thigh
    roots gets its pelvis tracker where the standard skeleton has its hips joint; a rig proportioned
    like the standard (every training clip) keeps its root exactly."""
    above = skeleton.STANDARD_HIPS_ABOVE_THIGH_ROOTS * 80.0
    c = skeleton.Clip(bvh.parse(rig_text(-10.0, 5.0)))
    assert c.units == 0.01
    np.testing.assert_allclose(c.hips_point, [0.0, (-10.0 + above) * 0.01, 0.05], atol=1e-12)
    P, _ = c.trackers()  # in the clip's world (no floor shift): root at (0, 1, 0) m, then (0.1, 1, 0.05) turned
    np.testing.assert_allclose(P[0, 3], [0.0, 1.0 + (-10.0 + above) * 0.01, 0.05], atol=1e-9)
    np.testing.assert_allclose(P[1, 3], [0.15, 1.0 + (-10.0 + above) * 0.01, 0.05], atol=1e-9)
    s = skeleton.Clip(bvh.parse(rig_text(-above, 0.0)))
    assert (s.hips_point == 0).all()
    P, _ = s.trackers()
    assert (P[:, 3] == s.pw[:, s.roles["hips"]]).all()
    near = skeleton.Clip(bvh.parse(rig_text(-above + 0.4, 0.0)))   # within 0.6 % of the leg: kept
    far = skeleton.Clip(bvh.parse(rig_text(-above + 0.6, 0.0)))
    assert (near.hips_point == 0).all() and abs(far.hips_point[1] - 0.006) < 1e-9
