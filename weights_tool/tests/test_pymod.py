"""The sparsebody Python module (weights_tool/native/module.cpp): its output is the demo's byte for
byte (the output BVH written from run()'s rows equals sparsebody_demo's file), batches split freely,
calibration control, the GIL released during a batch, and bad input answered with a Python exception.

Run by CTest as pymod_pytest (SPARSEBODY_PYMOD_REQUIRED=1: a module that cannot be imported fails
instead of skipping; SPARSEBODY_DEMO: the demo binary to compare with).
"""
import filecmp
import os
import subprocess
import threading
import time

import numpy as np
import pytest

from weights_tool import pymod

CLIP = "/usr/share/assimp/models/BVH/01_01.bvh"  # assimp-testmodels (.ci/install-deps.sh): 120 fps CMU walk
ROOT = pymod.ROOT


@pytest.fixture(scope="module")
def sb():
    m = pymod.load()
    if m is None:
        if os.environ.get("SPARSEBODY_PYMOD_REQUIRED"):
            pytest.fail("SPARSEBODY_PYMOD_REQUIRED is set but the sparsebody module cannot be imported")
        pytest.skip("the sparsebody module is not built (cmake --build build --target sparsebody_python)")
    return m


@pytest.fixture(scope="module")
def demo():
    d = os.environ.get("SPARSEBODY_DEMO") or os.path.join(ROOT, "build", "examples", "sparsebody_demo")
    if not os.path.exists(d):
        pytest.skip("sparsebody_demo is not built")
    return d


def need_clip():
    if not os.path.exists(CLIP):
        pytest.skip(f"{CLIP} missing (assimp-testmodels)")


def same(a, b):
    """Equal arrays, NaN where the other has NaN (rows without an output)."""
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


# The demo's options and the module's run: the output BVHs must be the same bytes.
CASES = [
    ["--model", "lobstr"],
    ["--model", "lobstr", "--storage", "float", "--mode", "window"],
    ["--model", "n3p"],
    ["--model", "n3p", "--no-contact-ik", "--storage", "f16"],
    ["--model", "n3p", "--physics"],
    ["--model", "lobstr", "--devices", "--device-seed", "7", "--devices-stand", "0"],
    ["--model", "n3p", "--physics", "--devices", "--device-seed", "7", "--devices-stand", "3"],
]


def _close(x, y, tol):
    """Tokens x, y equal, or both numbers within tol(|x|)."""
    if x == y:
        return True
    try:
        fx, fy = float(x), float(y)
    except ValueError:
        return False
    return abs(fx - fy) <= tol(abs(fx))


def same_output(ref, mine, physics=False):
    """True when the files are equal, or differ only in float rounding: the same tokens, every number
    within 1e-9 absolute + 1e-5 relative (the BVH prints 6 significant digits). The module and the demo
    are separate compilations; a different inlining may contract a multiply-add differently and move a
    value that should be 0 from -3.5e-15 to -2.1e-15 (seen on a fresh clone's build).
    physics: a simulation is chaotic, so such a rounding difference grows. GCC vectorised the same RNEA
    template differently in the two programs (same flags), contracted a different product of a cross
    product, and the outputs parted after 71-205 frames, by at most 0.016 (cm or deg) over the clip.
    So for the physics pipelines: the first 60 frames (2 s) to rounding, then every number within 0.1
    (1 mm, 0.1 deg)."""
    if filecmp.cmp(ref, mine, shallow=False):
        return True
    a, b = open(ref).read().split("\n"), open(mine).read().split("\n")
    if len(a) != len(b):
        return False
    motion = next((i for i, line in enumerate(a) if line.startswith("Frame Time")), len(a)) + 1
    for i, (la, lb) in enumerate(zip(a, b)):
        ta, tb = la.split(), lb.split()
        if len(ta) != len(tb):
            return False
        loose = physics and i >= motion + 60
        tol = (lambda m: 0.1) if loose else (lambda m: 1e-9 + 1e-5 * m)
        if not all(_close(x, y, tol) for x, y in zip(ta, tb)):
            return False
    return True
    a, b = open(ref).read().split(), open(mine).read().split()
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if x == y:
            continue
        try:
            fx, fy = float(x), float(y)
        except ValueError:
            return False
        if abs(fx - fy) > 1e-9 + 1e-5 * abs(fx):
            return False
    return True


@pytest.mark.parametrize("opts", CASES, ids=[" ".join(c[1:]) for c in CASES])
def test_output_bvh_equals_the_demos_byte_for_byte(sb, demo, tmp_path, opts):
    need_clip()
    ref, mine = tmp_path / "demo.bvh", tmp_path / "module.bvh"
    r = subprocess.run([demo, CLIP, "-o", str(ref), "--quiet"] + opts, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    run = pymod.run_clip(sb, CLIP, chunk=500, **pymod.demo_options(opts))
    sb.write_bvh(str(mine), run.pipe, run.out)
    assert len(run.shown()) > 500
    assert same_output(ref, mine, physics="--physics" in opts), f"{mine} differs from the demo's {ref}"


def constant_correction(path, bias):
    """An n3p_correction_policy whose every output is tanh(bias) (zero weights): a test double."""
    from weights_tool.format import write_weights
    sizes = [1008, 256, 256, 48]
    sd = {}
    for l in range(3):
        sd[f"layers.{l}.weight"] = np.zeros((sizes[l + 1], sizes[l]), np.float32)
        sd[f"layers.{l}.bias"] = np.full(sizes[l + 1], bias if l == 2 else 0.0, np.float32)
    write_weights(str(path), sd, "n3p_correction_policy", 1008, 48, meta={"action_scale": 0.2})
    return str(path)


def test_physics_correction_equals_the_demos(sb, demo, tmp_path):
    """--physics --correction FILE: the module's create(correction=FILE) writes the demo's BVH; the
    correction changes the motion; a kinematic pipeline refuses it."""
    need_clip()
    corr = constant_correction(tmp_path / "corr.json", 0.3)
    ref, mine, plain = tmp_path / "demo.bvh", tmp_path / "module.bvh", tmp_path / "plain.bvh"
    opts = ["--model", "n3p", "--physics", "--correction", corr]
    r = subprocess.run([demo, CLIP, "-o", str(ref), "--quiet"] + opts, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    run = pymod.run_clip(sb, CLIP, **pymod.demo_options(opts))
    assert run.pipe.summary()["corrections"] > 500
    sb.write_bvh(str(mine), run.pipe, run.out)
    assert same_output(ref, mine, physics=True)
    base = pymod.run_clip(sb, CLIP, physics=True, model="n3p")
    sb.write_bvh(str(plain), base.pipe, base.out)
    assert not same_output(mine, plain)
    with pytest.raises(ValueError, match="physics mode"):
        sb.create("n3p", correction=corr)
    r = subprocess.run([demo, CLIP, "-o", str(ref), "--quiet", "--model", "n3p", "--correction", corr], capture_output=True, text=True)
    assert r.returncode != 0 and "--correction" in r.stderr


def test_tracker_csv_path_equals_the_demos(sb, demo, tmp_path):
    """--trackers-out writes the same CSV, and the CSV read back drives the same output."""
    need_clip()
    dev = ["--devices", "--device-seed", "3", "--devices-stand", "1"]
    csv_d, csv_m = tmp_path / "demo.csv", tmp_path / "module.csv"
    r = subprocess.run([demo, CLIP, "-o", str(tmp_path / "x.bvh"), "--quiet", "--trackers-out", str(csv_d)] + dev,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    sb.read_input(CLIP, devices=True, device_seed=3, devices_stand=1.0, trackers_out=str(csv_m))
    assert filecmp.cmp(csv_d, csv_m, shallow=False)
    r = subprocess.run([demo, str(csv_d), "-o", str(tmp_path / "demo.bvh"), "--quiet", "--model", "n3p"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    run = pymod.run_clip(sb, str(csv_m), "n3p")
    assert not run.inp["has_truth"]
    sb.write_bvh(str(tmp_path / "module.bvh"), run.pipe, run.out)
    assert same_output(tmp_path / "demo.bvh", tmp_path / "module.bvh")


@pytest.mark.parametrize("model", ["lobstr", "n3p", "n3p_physics"])
def test_batches_split_freely(sb, model):
    """Any batch sizes give the rows of one batch, bit for bit (the pipeline carries its state)."""
    need_clip()
    whole = pymod.run_clip(sb, CLIP, model, devices=True, device_seed=2)
    parts = pymod.run_clip(sb, CLIP, model, devices=True, device_seed=2, chunk=97)
    assert whole.out.keys() == parts.out.keys()
    for k in whole.out:
        assert same(whole.out[k], parts.out[k]), k
    T, J = len(whole.inp["time"]), len(whole.pipe.joint_names)
    o = whole.out
    assert o["position"].shape == (T, J, 3) and o["rotation"].shape == (T, J, 4) and o["contact"].shape == (T, 2)
    shown = o["has_output"]
    assert np.isfinite(o["position"][shown]).all() and np.isnan(o["position"][~shown]).all()
    # (x, y, z, w) unit quaternions; the root's local rotation is its world rotation
    assert np.allclose(np.linalg.norm(o["rotation"][shown], axis=-1), 1, atol=1e-6)
    assert same(o["rotation"][:, 0], o["world_rotation"][:, 0])
    # world positions are the pipeline's at the user's size: the root is root x user_scale
    assert np.allclose(o["position"][shown, 0], o["root"][shown] * o["user_scale"][shown, None], atol=1e-12)
    assert o["contact"].any() and (~o["contact"]).any()
    if model == "n3p_physics":
        assert np.nanmean(o["residual_force"]) > 0 and "residual_force" in o
        sm = whole.pipe.summary()
        # 4 substeps (120 Hz) per 30 Hz frame, less the frames before the first output or cut short by a failure
        n = 4 * int(o["steps"].sum())
        assert n - 8 <= sm["residual_steps"] <= n, (sm, n)
    else:
        assert "residual_force" not in o


def standing(seconds=3.0, rate=72.0, eye=1.62):
    """A user standing still (3 mm sway) in OpenXR stage space: time, position, orientation, valid."""
    t = np.arange(int(seconds * rate)) / rate
    P = np.zeros((len(t), 4, 3), np.float32)
    Q = np.zeros((len(t), 4, 4), np.float32)
    Q[..., 3] = 1
    sway = 0.003 * np.sin(np.pi * t)
    for k, (x, y, z) in enumerate([(0, eye, 0), (-0.25, 0.95, -0.1), (0.25, 0.95, -0.1), (0, 0.95, 0)]):
        P[:, k] = np.stack([x + sway, y + 0 * t, z + 0 * t], axis=-1)
    return t, P, Q, np.ones((len(t), 4), bool)


@pytest.mark.parametrize("model", ["lobstr", "n3p"])
def test_calibration_controllers_on_a_table(sb, model):
    """Controllers lying flat (a quarter turn about X) while the user stands: the stand sizes the body,
    the controllers keep the device model's offsets and the report says so."""
    t, P, Q, V = standing()
    Q[:, 1:3] = [np.sin(np.pi / 4), 0, 0, np.cos(np.pi / 4)]
    p = sb.create(model)
    p.run(t, P, Q, V)
    rep = p.calibration_report()
    assert rep["status"] == "calibrated" and rep["eye_height"] == pytest.approx(1.62, abs=0.005)
    assert rep["grip_default"] == (True, True) and rep["grips_not_held"] >= 2
    assert "both grips not seen held" in rep["message"]


@pytest.mark.parametrize("model", ["lobstr", "n3p", "n3p_physics"])
def test_stand_ups_counted(sb, model):
    """3 s standing, 3 s seated (headset 0.45 m lower, controllers on the lap), a 1 s rise, 2 s
    standing: one stand-up (trackers/stand_up.hpp); a session that stays standing has none."""
    t, P, Q, V = standing(9.0)
    down = np.where(t < 3, 0.0, np.where(t < 6, 1.0, np.where(t < 7, 0.5 + 0.5 * np.cos(np.pi * (t - 6)), 0.0)))
    P[:, 0, 1] -= 0.45 * down
    P[:, 1:3, 1] -= 0.4 * down[:, None]
    P[:, 3, 1] -= 0.47 * down
    p = sb.create(model)
    assert p.stand_ups == 0
    p.run(t, P, Q, V)
    assert p.stand_ups == 1
    q = sb.create(model)
    q.run(*standing(9.0))
    assert q.stand_ups == 0


@pytest.mark.parametrize("model", ["lobstr", "n3p", "n3p_physics"])
def test_calibration_control(sb, model):
    t, P, Q, V = standing()
    p = sb.create(model)
    rep = p.calibration_report()
    assert rep["status"] == "default" and rep["source"] == "none" and "default body" in rep["message"]
    out = p.run(t, P, Q, V)
    rep = p.calibration_report()
    assert rep["status"] == "calibrated" and rep["source"] == "automatic", rep
    assert rep["stature"] == pytest.approx(1.62 / 0.936, abs=0.01) and rep["eye_height"] == pytest.approx(1.62, abs=0.005)
    assert rep["first_time"] < 0.5 and rep["windows"] == 1
    assert rep["grip_default"] == (False, False) and rep["grips_not_held"] == 0  # held as at a stand
    assert out["calibration"][0] == 0 and out["calibration"][-1] == 1  # per row: default body, then calibrated
    auto_scale = p.user_scale
    assert auto_scale == pytest.approx(1 / rep["scale"])
    p.recalibrate()
    assert p.calibration_report()["status"] == "default"
    # explicit: one standing frame, then a plain scale (trackers at the joints)
    assert p.calibrate(t[10], P[10], Q[10], V[10])
    assert p.calibration_report()["source"] == "explicit"
    assert p.user_scale == pytest.approx(auto_scale, rel=0.02)
    s = p.fit_leg_length(0.9)
    assert p.calibration_report()["source"] == "application" and abs(p.user_scale - 1 / s) < 1e-12
    bad = V[10].copy()
    bad[0] = False  # no headset: cannot calibrate, unchanged
    assert not p.calibrate(t[10], P[10], Q[10], bad)
    assert p.calibration_report()["source"] == "application"


def test_trackers_at_the_joints_take_the_clips_proportions(sb):
    """read_input's lengths and fit_leg_length(leg, torso, arm), as the demo: LoBSTr's output skeleton
    in the clip's torso and arms (leg length by the scale), Neural3Points' arms only."""
    need_clip()
    inp = sb.read_input(CLIP)
    L = inp["lengths"]
    assert L["leg"] == pytest.approx(inp["leg"], rel=1e-6) and L["torso"] > 0 and L["arm"] > 0
    p = sb.create("lobstr")
    ref = sb.create("lobstr")
    s = p.fit_leg_length(inp["leg"], L["torso"] * 1.1, L["arm"])
    ref.fit_leg_length(inp["leg"])
    assert ref.body_proportions == {"leg": 1.0, "torso": 1.0, "arm": 1.0}
    b = p.body_proportions
    assert b["leg"] == 1.0
    torso = s * L["torso"] * 1.1  # the clip's torso at the standard size, against the standard's hips-to-head
    assert b["torso"] == pytest.approx(torso / np.linalg.norm(_rest(ref, ref.roles["head"])), rel=1e-6), b
    n = sb.create("n3p")
    n.fit_leg_length(inp["leg"], L["torso"] * 1.1, L["arm"] * 1.1)
    assert n.body_proportions["torso"] == 1.0 and n.body_proportions["arm"] > 1.0


def _rest(p, j):
    """Rest position of joint j relative to the root (sum of offsets)."""
    v = np.zeros(3)
    while j > 0:
        v += p.offsets[j]
        j = p.parents[j]
    return v


def test_gil_is_released_during_a_batch(sb):
    """Another Python thread runs while a batch runs (a held GIL would stop it for the whole batch)."""
    need_clip()
    inp = sb.read_input(CLIP)
    args = [np.tile(a, (4,) + (1,) * (a.ndim - 1)) for a in (inp["time"], inp["position"], inp["orientation"], inp["valid"])]
    n = len(inp["time"])
    args[0] = np.concatenate([inp["time"] + k * (inp["time"][-1] + 1) for k in range(4)])  # 4 sessions, 1 s gaps
    p = sb.create("n3p_physics")
    ticks, done = [0], threading.Event()

    def count():
        while not done.is_set():
            ticks[0] += 1

    t = threading.Thread(target=count)
    t.start()
    t0 = time.perf_counter()
    before = ticks[0]
    out = p.run(*args)
    during = ticks[0] - before
    dt = time.perf_counter() - t0
    done.set()
    t.join()
    assert out["has_output"].sum() > 3 * n
    assert dt > 0.05 and during > 1000, (dt, during)


def test_bad_input_raises_a_clear_python_exception(sb):
    need_clip()
    inp = sb.read_input(CLIP)
    tm, P, Q, V = inp["time"][:50], inp["position"][:50], inp["orientation"][:50], inp["valid"][:50]
    p = sb.create("lobstr")
    p.fit_leg_length(inp["leg"])
    with pytest.raises(ValueError, match=r"position must have shape \[T, K, 3\] with T = 50 and K = 3 or 4, got \(50, 4, 2\)"):
        p.run(tm, P[..., :2], Q, V)
    with pytest.raises(ValueError, match=r"orientation must have shape \[T, K, 4\] = \(50, 4, 4\) \(x, y, z, w\), got \(50, 4, 3\)"):
        p.run(tm, P, Q[..., :3], V)
    with pytest.raises(ValueError, match=r"valid must have shape \[T, K\] = \(50, 4\), got \(50,\)"):
        p.run(tm, P, Q, V[:, 0])
    with pytest.raises(ValueError, match=r"time must have shape \[T\]"):
        p.run(tm[:, None], P, Q, V)
    with pytest.raises(ValueError, match="T = 49"):
        p.run(tm[:49], P, Q, V)
    with pytest.raises(TypeError):
        p.run(tm, "not an array", Q, V)
    Pn = P.copy()
    Pn[7, 2, 1] = np.nan
    with pytest.raises(ValueError, match=r"frame 7, tracker 2 \(right_hand\): position is nan in a pose marked valid"):
        p.run(tm, Pn, Q, V)
    Qn = Q.copy()
    Qn[3, 0, 3] = np.inf
    with pytest.raises(ValueError, match=r"frame 3, tracker 0 \(head\): orientation is inf"):
        p.run(tm, P, Qn, V)
    tn = tm.copy()
    tn[4] = tn[3]
    with pytest.raises(ValueError, match="frame 4: timestamp .* does not increase"):
        p.run(tn, P, Q, V)
    tn[4] = np.nan
    with pytest.raises(ValueError, match="frame 4: timestamp is nan"):
        p.run(tn, P, Q, V)
    # a rejected batch changed nothing: the same frames now give a fresh pipeline's rows
    fresh = sb.create("lobstr")
    fresh.fit_leg_length(inp["leg"])
    a, b = p.run(tm, P, Q, V), fresh.run(tm, P, Q, V)
    assert all(same(a[k], b[k]) for k in a)
    with pytest.raises(ValueError, match="does not increase"):  # times continue from the last batch
        p.run(tm, P, Q, V)
    # strict=False: the pipeline's own answer (the sanitiser holds the last pose), never a crash
    Vn = np.ones_like(V)
    Pn = inp["position"][50:100].copy()
    Pn[5:9] = np.nan
    out = p.run(inp["time"][50:100], Pn, inp["orientation"][50:100], Vn, strict=False)
    assert out["has_output"].all() and np.isfinite(out["position"]).all()
    # the same NaN in a tracker marked lost is accepted in strict mode
    p.reset()
    Vn[5:9, 1] = False
    Pn[5:9] = inp["position"][55:59]
    Pn[5:9, 1] = np.nan
    assert np.isfinite(p.run(inp["time"][50:100], Pn, inp["orientation"][50:100], Vn)["position"]).all()
    with pytest.raises(ValueError, match="leg length must be finite"):
        p.fit_leg_length(float("nan"))
    with pytest.raises(ValueError, match="position must have shape \\[K, 3\\]"):
        p.calibrate(0.0, P[0, :, :2], Q[0], V[0])
    with pytest.raises(ValueError, match="model must be lobstr, n3p or n3p_physics"):
        sb.create("lobster")
    with pytest.raises(ValueError, match="storage must be auto, float, f16 or q8"):
        sb.create("n3p", storage="int4")
    with pytest.raises(ValueError, match="window is LoBSTr-only"):
        sb.create("n3p", mode="window")
    with pytest.raises(OSError, match="nowhere.json"):
        sb.create("lobstr", weights="/nowhere.json")
    with pytest.raises(OSError, match="missing.bvh"):
        sb.read_input("/tmp/missing.bvh")
    with pytest.raises(ValueError, match="LoBSTr needs one"):
        pymod.run_clip(sb, CLIP, "lobstr", no_pelvis=True)


def test_three_tracker_batches(sb):
    """K = 3 (no pelvis column): the rows of the pelvis marked lost."""
    need_clip()
    inp = sb.read_input(CLIP, devices=True)
    a = [inp["time"], inp["position"][:, :3], inp["orientation"][:, :3], inp["valid"][:, :3]]
    ref = pymod.run_clip(sb, CLIP, "n3p", devices=True).out
    n3 = sb.create("n3p").run(*a)
    assert all(same(n3[k], ref[k]) for k in n3)  # N3P ignores the pelvis tracker
    V = inp["valid"].copy()
    V[:, 3] = False
    lo3, lo4 = sb.create("lobstr").run(*a), sb.create("lobstr").run(inp["time"], inp["position"], inp["orientation"], V)
    assert all(same(lo3[k], lo4[k]) for k in lo3)


def test_questsim_with_explicit_weights(sb, tmp_path):
    """QuestSim needs explicit weights (only random test weights exist): bodies out, deterministic."""
    need_clip()
    pytest.importorskip("torch")
    w = tmp_path / "questsim_policy.json"
    r = subprocess.run(["/usr/bin/python3", "-m", "weights_tool.questsim", "policy", "--bodies", "21", "--joint-dofs", "48",
                        "--future", "6", "--seed", "7", "--out", str(w)], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    inp = sb.read_input(CLIP, devices=True)
    a = (inp["time"], inp["position"][:, :3], inp["orientation"][:, :3], inp["valid"][:, :3])
    q1, q2 = sb.QuestSim(str(w), 1.75), sb.QuestSim(str(w), 1.75)
    o1, o2 = q1.run(*a), q2.run(*a)
    B = len(q1.bodies)
    assert B == 21 and o1["body_position"].shape == (len(a[0]), B, 3)
    assert all(same(o1[k], o2[k]) for k in o1)
    assert np.isfinite(o1["body_position"]).all() and o1["ticks"].sum() > 0
    ev = o1["event"][o1["ticks"] > 0]
    assert (ev == 0).mean() > 0.5  # mostly plain steps (random weights fall now and then)
    with pytest.raises(ValueError, match="height must be"):
        sb.QuestSim(str(w), float("nan"))
    with pytest.raises(OSError):
        sb.QuestSim("/nowhere.json", 1.75)


def test_questsim_evaluation_counts_each_fall_once(sb):
    """QuestSim.run's `event` repeats a tick's event on the input frames that run no tick (72 Hz input,
    36 Hz ticks), so counting it over all frames counted every fall twice; the evaluation's count
    (evaluate.run_policy) equals the Fall events of the frames that ticked."""
    need_clip()
    from weights_tool.questsim import evaluate
    policy = os.path.join(ROOT, "examples", "weights", "questsim_policy.json")
    inp = sb.read_input(CLIP, devices=True)
    _, out, _, falls, failures = evaluate.run_policy(sb, policy, inp)
    ticked = out["ticks"] > 0
    assert out["ticks"].max() == 1  # one tick at most per frame: the ticking frames hold every event
    assert falls > 0  # the CMU playground clip makes the shipped policy fall
    assert falls == int((out["event"][ticked] == 5).sum())
    assert failures == int((out["event"][ticked] == 4).sum())
    assert int((out["event"] == 5).sum()) == 2 * falls  # what counting every frame gave


def test_one_batch_at_a_time_per_pipeline(sb):
    """A second thread calling run() on a pipeline that is mid-batch gets RuntimeError; an empty
    batch is a no-op (so probing changes nothing)."""
    need_clip()
    inp = sb.read_input(CLIP)
    n = len(inp["time"])
    args = [np.tile(a, (4,) + (1,) * (a.ndim - 1)) for a in (inp["time"], inp["position"], inp["orientation"], inp["valid"])]
    args[0] = np.concatenate([inp["time"] + k * (inp["time"][-1] + 1) for k in range(4)])
    empty = [a[:0] for a in args]
    p = sb.create("n3p_physics")
    e0 = p.run(*empty)
    assert e0["position"].shape == (0, len(p.joint_names), 3)
    result, errors = {}, []

    def long_batch():
        result["out"] = p.run(*args)

    t = threading.Thread(target=long_batch)
    t.start()
    while t.is_alive():
        try:
            p.run(*empty)
        except RuntimeError as e:
            errors.append(str(e))
            break
        time.sleep(0.001)
    t.join()
    assert errors and "running a batch in another thread" in errors[0]
    ref = sb.create("n3p_physics").run(*args)  # the probing changed nothing
    assert all(same(result["out"][k], ref[k]) for k in ref)
    assert result["out"]["has_output"].sum() > 3 * n


def test_foot_pin(sb):
    """foot_pin: 'toe' (the default) or 'ankle' give different feet; anything else is a ValueError."""
    need_clip()
    toe = pymod.run_clip(sb, CLIP, model="n3p", no_pelvis=True)
    ankle = pymod.run_clip(sb, CLIP, model="n3p", no_pelvis=True, **pymod.demo_options(["--foot-pin", "ankle"]))
    assert toe.out["position"].shape == ankle.out["position"].shape
    assert not np.array_equal(toe.out["position"], ankle.out["position"])
    with pytest.raises(ValueError, match="foot_pin must be ankle or toe, got 'heel'"):
        sb.create("n3p", foot_pin="heel")


def test_storage_auto_and_the_int8_kernel_in_use_are_named(sb):
    # storage auto's choice with its reason, and the int8 kernel q8 weights run here: the build's
    # own or the CPU's run-time upgrade (nn/int8.hpp), never an empty or unknown name.
    storage, reason = sb.fastest_storage()
    assert storage in ("float", "f16", "q8") and reason
    kernel = sb.q8_kernel_in_use()
    known = ("AVX-512 VNNI", "AVX-VNNI", "AVX2", "NEON dot product", "NEON", "portable")
    assert kernel.startswith(known), kernel
