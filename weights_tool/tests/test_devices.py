"""Device-realistic synthesis (weights_tool/devices.py), retargeted bodies (bodies.py) and the
off-distribution comparator (offdist.py), on a CMU clip from Debian's assimp-testmodels."""
import os

import numpy as np
import pytest

from weights_tool import bodies, devices, offdist
from weights_tool.lobstr.skeleton import Clip

CMU = "/usr/share/assimp/models/BVH/01_01.bvh"
pytestmark = pytest.mark.skipif(not os.path.exists(CMU), reason="assimp-testmodels not installed")


def short_clip(tmp_path, frames=120):
    """The first `frames` frames of the CMU clip as a BVH file (keeps the tests fast), relabelled as
    30 fps (the pipelines' rate, so the comparator matches frames one to one)."""
    text = open(CMU).read()
    head, motion = text.split("MOTION", 1)
    lines = motion.strip().splitlines()
    out = tmp_path / "short.bvh"
    out.write_text(head + "MOTION\nFrames: %d\nFrame Time: 0.0333333\n" % frames + "\n".join(lines[2:2 + frames]) + "\n")
    return str(out)


def test_nominal_devices_are_the_joint_trackers_and_scale(tmp_path):
    clip = Clip(short_clip(tmp_path))
    aug = devices.Augment(np.random.default_rng(0), body=False, speed=False, devices=False)
    P, Q, s = devices.device_trackers(clip, aug, noise=False)
    P0, Q0 = clip.trackers()
    P0 = P0.copy()
    P0[..., 1] -= clip.floor()
    np.testing.assert_allclose(P[:, :3], P0[:, :3], atol=1e-12)   # nominal offsets cancel exactly
    np.testing.assert_allclose(Q, Q0, atol=1e-12)
    head_joint = P0[0, 0, 1]
    assert s == pytest.approx(devices.STANDARD["standing_head_height"] / head_joint)
    # the belt tracker lands at the standard standing hips height at the calibration frame
    assert P[0, 3, 1] * s == pytest.approx(devices.STANDARD["standing_hips_height"])


def test_device_offsets_and_losses(tmp_path):
    clip = Clip(short_clip(tmp_path))
    rng = np.random.default_rng(3)
    aug = devices.Augment(rng, body=False, speed=False)
    P, Q, s = devices.device_trackers(clip, aug, noise=False)
    P0, _ = clip.trackers()
    d = np.linalg.norm(P[:, :3] - (P0[:, :3] - [0, clip.floor(), 0]), axis=-1)
    # residual of the user's offsets after the nominal ones are taken off: a few cm, never more than
    # the offsets' ranges allow (eye +-2 cm per axis, grip 12 cm + nominal 8.5 cm, plus jitter)
    # (a short loss holds a controller where it was: those frames are further off)
    assert np.median(d[:, 0]) < 0.05 and np.median(d[:, 1:]) < 0.15
    assert np.all(np.isfinite(P)) and np.all(np.isfinite(Q))


def test_scaled_body_keeps_feet_on_floor_and_scales_stature(tmp_path):
    clip = Clip(short_clip(tmp_path))
    for st in (1.55, 1.90):
        aug = devices.Augment(np.random.default_rng(1), body=False, speed=False, devices=False)
        aug.stature = st
        big = devices.scale_body(clip, aug)
        k = st / devices.STANDARD_STATURE
        assert big.leg == pytest.approx(clip.leg * k)
        h0 = clip.pw[0, clip.roles["head"], 1] - clip.floor()
        h1 = big.pw[0, big.roles["head"], 1] - big.floor()
        assert h1 == pytest.approx(h0 * k, rel=0.01)


def test_retime_changes_length_not_pose_range(tmp_path):
    clip = Clip(short_clip(tmp_path))
    fast = devices.retime(clip, 1.2)
    assert fast.frames == int(np.floor((clip.frames - 1) / 1.2)) + 1
    R = fast.R_local
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-9)


def test_bodies_bvh_and_offdist_compare(tmp_path):
    src = short_clip(tmp_path)
    out = tmp_path / "big"
    os.makedirs(out)
    with open(src) as f:
        # (the leg / torso / arm ratios apply to the standard skeleton's joint names; a CMU clip scales as a whole)
        (out / "short.bvh").write_text(bodies.scale_text(f.read(), src, 1.90))
    a = Clip(src)
    b = Clip(str(out / "short.bvh"), units=a.units)
    k = 1.90 / devices.STANDARD_STATURE
    assert b.leg == pytest.approx(a.leg * k, rel=1e-4)
    m = offdist.compare(str(out / "short.bvh"), str(out / "short.bvh"), truth_units=a.units, out_units=a.units)
    # the same clip: the only difference is the floor the comparator takes off the clip (the demo's
    # output has its floor at y = 0 already)
    assert m["mpjpe"][0] / m["mpjpe"][1] == pytest.approx(abs(b.floor()), abs=1e-9)
    m2 = offdist.compare(src, str(out / "short.bvh"), truth_units=a.units, out_units=a.units)
    assert m2["mpjpe"][0] / m2["mpjpe"][1] > 0.01  # a different body: an error the comparator sees


def test_offdist_moving_leaves_out_the_held_stand(tmp_path):
    src = short_clip(tmp_path, frames=60)
    c = Clip(src)
    P = c.pw[:, [c.roles[k] for k in offdist.ROLES]].copy()
    P[..., 1] -= c.floor()
    # a stand of 1 s (30 rows) holding frame 10, 5 cm off; the clip's own motion exact around it
    held = np.repeat(P[10:11] + np.array([0.0, 0.03, 0.04]), 30, axis=0)
    rows = np.concatenate([P[:10], held, P[10:]])
    m = offdist.compare_positions(rows, src, hold=(10 / 30.0, 1.0))
    # (the comparator takes the floor off the clip as the run showed it, stand included: < 0.1 mm apart)
    assert m["moving"][1] == 60 * 12 and m["moving"][0] / m["moving"][1] < 1e-4
    assert m["mpjpe"][0] / m["mpjpe"][1] == pytest.approx(0.05 * 30 / 90, abs=1e-4)
    m0 = offdist.compare_positions(P, src)  # no stand: moving is the MPJPE
    assert m0["moving"] == m0["mpjpe"]


def test_offdist_controllers_on_a_table(tmp_path):
    """table mode's session: the first sample's headset held, the controllers flat on the table (a
    quarter turn from their first orientation) then picked up to their first sample, the session's
    own samples after it unchanged and time-shifted."""
    cols = ["time"] + [f"{n}_{a}" for n in ("head", "left_hand", "right_hand")
                       for a in ("px", "py", "pz", "qx", "qy", "qz", "qw", "valid")]
    rows = []
    for i in range(10):
        r = [i / 72.0]
        for p in ((0.1, 1.6, 0.2), (-0.2, 0.9, 0.1), (0.3, 0.9, 0.1)):
            r += [p[0] + 0.01 * i, p[1], p[2], 0.0, 0.0, 0.0, 1.0, 1]
        rows.append(r)
    path = tmp_path / "s.csv"
    path.write_text("# a comment\n" + ",".join(cols) + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    offdist.controllers_on_a_table(str(path), seconds=1.0, pickup=0.5)
    lines = path.read_text().splitlines()
    assert lines[0] == "# a comment" and lines[1] == ",".join(cols)
    out = np.array([[float(x) for x in l.split(",")] for l in lines[2:]])
    c = {n: i for i, n in enumerate(cols)}
    n_pre = 72 + 36
    assert len(out) == n_pre + 10
    np.testing.assert_allclose(np.diff(out[:, 0]), 1 / 72.0, atol=1e-6)
    assert out[0, 0] == 0
    np.testing.assert_allclose(out[n_pre:, 1:], np.array(rows)[:, 1:], atol=1e-8)  # the session, unchanged
    for side in ("left_hand", "right_hand"):
        P = out[:, [c[f"{side}_p{a}"] for a in "xyz"]]
        Q = out[:, [c[f"{side}_q{a}"] for a in "xyzw"]]
        np.testing.assert_allclose(P[:72, 1], 0.76, atol=1e-8)                     # on the table
        assert np.abs(P[:72, 2] - (0.2 - 0.45)).max() < 1e-8                       # 0.45 m ahead (-Z)
        np.testing.assert_allclose(np.abs(Q[:72, 0]), np.sin(np.pi / 4), atol=1e-8)  # flat: a quarter turn about X
        np.testing.assert_allclose(P[n_pre - 1], P[n_pre], atol=0.02)             # picked up to the first sample
        assert np.all(np.abs(np.linalg.norm(Q, axis=1) - 1) < 1e-8)
    np.testing.assert_allclose(out[:n_pre, c["head_px"]], rows[0][c["head_px"]])  # the headset held


def test_offdist_seated_start(tmp_path):
    """seated mode's session: the headset 0.42 m lower and 0.1 m ahead, the belt 0.47 m lower, the
    controllers on the lap at 0.62 m, then a stand-up to the first sample; the session unchanged."""
    cols = ["time"] + [f"{n}_{a}" for n in ("head", "left_hand", "right_hand", "pelvis")
                       for a in ("px", "py", "pz", "qx", "qy", "qz", "qw", "valid")]
    rows = []
    for i in range(10):
        r = [i / 72.0]
        for p in ((0.1, 1.6, 0.2), (-0.2, 0.9, 0.1), (0.3, 0.9, 0.1), (0.1, 0.95, 0.2)):
            r += [p[0], p[1], p[2] - 0.01 * i, 0.0, 0.0, 0.0, 1.0, 1]
        rows.append(r)
    path = tmp_path / "s.csv"
    path.write_text(",".join(cols) + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    offdist.seated_start(str(path), seconds=1.0, rise=0.5)
    out = np.array([[float(x) for x in l.split(",")] for l in path.read_text().splitlines()[1:]])
    c = {n: i for i, n in enumerate(cols)}
    n_pre = 72 + 36
    assert len(out) == n_pre + 10 and out[0, 0] == 0
    np.testing.assert_allclose(np.diff(out[:, 0]), 1 / 72.0, atol=1e-6)
    np.testing.assert_allclose(out[n_pre:, 1:], np.array(rows)[:, 1:], atol=1e-8)
    np.testing.assert_allclose(out[:72, c["head_py"]], 1.6 - 0.42, atol=1e-8)
    assert np.all(np.abs(out[:72, c["head_pz"]] - (0.2 - 0.1)) < 1e-8)       # 0.1 m ahead (-Z)
    assert np.abs(out[:72, c["head_px"]] - 0.1).max() > 0.001                 # sway
    np.testing.assert_allclose(out[:72, c["pelvis_py"]], 0.95 - 0.47, atol=1e-8)
    for side in ("left_hand", "right_hand"):
        np.testing.assert_allclose(out[:72, c[f"{side}_py"]], 0.62, atol=1e-8)
        np.testing.assert_allclose(out[:72, c[f"{side}_pz"]], 0.1 - 0.3, atol=1e-8)
    np.testing.assert_allclose(out[n_pre - 1, 1:], out[n_pre, 1:], atol=0.05)  # stood up to the first sample


def test_offdist_look_down_at_start(tmp_path):
    """lookdown mode's session: the headset pitched down 25 deg about the head joint (the headset less
    the device model's eye offset stays put) for 2 s, back to the session's own over 0.5 s; every other
    column unchanged."""
    cols = ["time"] + [f"{n}_{a}" for n in ("head", "left_hand", "right_hand")
                       for a in ("px", "py", "pz", "qx", "qy", "qz", "qw", "valid")]
    yaw = np.radians(40.0)  # the headset turned 40 deg to the left: pitch about its own X
    qh = [0.0, np.sin(yaw / 2), 0.0, np.cos(yaw / 2)]
    rows = [[i / 72.0] + [0.1, 1.6, 0.2 - 0.01 * i] + qh + [1] + [-0.2, 0.9, 0.1, 0, 0, 0, 1, 1] + [0.3, 0.9, 0.1, 0, 0, 0, 1, 1]
            for i in range(3 * 72)]
    path = tmp_path / "s.csv"
    path.write_text(",".join(cols) + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    offdist.look_down_at_start(str(path))
    out = np.array([[float(x) for x in l.split(",")] for l in path.read_text().splitlines()[1:]])
    src = np.array(rows)
    c = {n: i for i, n in enumerate(cols)}
    P, Q = [c[f"head_p{a}"] for a in "xyz"], [c[f"head_q{a}"] for a in "xyzw"]
    joint = lambda r: r[:, P] - offdist._qrot(r[:, Q], offdist.EYE_OPENXR)
    np.testing.assert_allclose(joint(out), joint(src), atol=1e-9)              # about the head joint
    fwd = offdist._qrot(out[:, Q], np.array([0.0, 0.0, -1.0]))
    pitch = np.degrees(np.arcsin(-fwd[:, 1]))
    np.testing.assert_allclose(pitch[:144], 25.0, atol=1e-6)                      # looking down 2 s
    np.testing.assert_allclose(out[180:], src[180:], atol=1e-9)                   # the session's own from 2.5 s
    assert np.all(np.diff(pitch[144:181]) <= 1e-9)                               # looking up in between
    heading = np.degrees(np.arctan2(-fwd[:, 0], -fwd[:, 2]))
    np.testing.assert_allclose(heading, 40.0, atol=1e-6)                         # the heading kept
    keep = [i for i, n in enumerate(cols) if not n.startswith("head_p") and not n.startswith("head_q")]
    np.testing.assert_allclose(out[:, keep], src[:, keep], atol=1e-9)
