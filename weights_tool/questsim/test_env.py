"""The Python binding of the QuestSim training environment (_questsim_env, questsim_env.hpp) on real
validation clips: zero-copy views, shapes, determinism, bad input, and one PPO update of the trainer
(C++ behaviour itself: tests/training/test_questsim_env.cpp)."""
import os
import tarfile

import numpy as np
import pytest

from .env import ROOT, load_module

TAR = os.path.join(ROOT, "..", "shared", "data", "bandai-namco", "validation.tar.xz")
N3P_LOWER = os.path.join(ROOT, "examples", "weights", "n3p_lower.json")
qe = load_module()


@pytest.fixture(scope="module")
def clip_paths(tmp_path_factory):
    if not os.path.exists(TAR):
        pytest.skip(f"{TAR} not found")
    out = tmp_path_factory.mktemp("clips")
    want, got = ["raise-up-both", "_walk_", "wave-left"], {}
    with tarfile.open(TAR) as t:
        for m in t:
            name = os.path.basename(m.name)
            w = next((w for w in want if w in name and w not in got), None)
            if w and name.endswith(".bvh"):
                t.extract(m, out)
                got[w] = os.path.join(out, m.name)
            if len(got) == len(want):
                break
    return [got[w] for w in want]


@pytest.fixture(scope="module")
def clips(clip_paths):
    return qe.load_clips(clip_paths, N3P_LOWER)


def test_views_are_zero_copy_and_shaped(clips):
    env = qe.Env(clips, [1.75, 1.6, 1.9], 1)
    assert len(clips) == 3 and all(clips.frames(i) > 50 for i in range(3))
    obs = env.obs
    assert obs.shape == (3, qe.Env.obs_size) and obs.dtype == np.float32
    assert env.reward.shape == (3,) and env.terminated.shape == (3,) and env.reward_terms.shape == (3, 5)
    before = obs.copy()
    env.step(np.zeros((3, qe.Env.action_size), np.float32))
    assert not np.array_equal(before, obs)  # the same buffer, updated in place
    assert np.all(np.isfinite(obs)) and np.all((env.reward >= 0) & (env.reward <= 1))
    assert obs[:, -1] == pytest.approx([1.75, 1.6, 1.9])  # o_user,scale = each avatar's height


def test_same_seed_same_bits_any_thread_count(clips):
    a, b = qe.Env(clips, [1.75] * 8, 4), qe.Env(clips, [1.75] * 8, 4)
    rng = np.random.default_rng(0)
    for _ in range(40):
        u = (0.05 * rng.standard_normal((8, qe.Env.action_size))).astype(np.float32)
        a.step(u, 1)
        b.step(u, 2)
        assert np.array_equal(a.obs, b.obs) and np.array_equal(a.reward, b.reward)
        assert np.array_equal(a.terminated, b.terminated) and np.array_equal(a.truncated, b.truncated)


def test_bad_input_raises(clips):
    env = qe.Env(clips, [1.75] * 2, 0)
    with pytest.raises(ValueError, match=r"actions: expected float32 \[2, 48\]"):
        env.step(np.zeros((3, qe.Env.action_size), np.float32))
    env.step(np.full((2, qe.Env.action_size), np.nan, np.float32))  # non-finite actions: zero torques
    assert np.all(np.isfinite(env.obs))
    with pytest.raises(ValueError, match="height out of range"):
        qe.Env(clips, [0.1], 0)
    cmu = "/usr/share/assimp/models/BVH/01_01.bvh"
    if os.path.exists(cmu):  # another skeleton: the retarget needs the standard skeleton's joints
        with pytest.raises(Exception, match="01_01.bvh.*missing"):
            qe.load_clips([cmu], N3P_LOWER)
    with pytest.raises(Exception, match="nonexistent.bvh"):
        qe.load_clips(["/nonexistent.bvh"], N3P_LOWER)


def test_trainer_runs_one_update_resumes_and_exports(clip_paths, tmp_path):
    from . import train
    d = os.path.dirname(clip_paths[0])
    args = [d, "--out", str(tmp_path), "--envs", "8", "--horizon", "8", "--samples", "640", "--motions", "."]
    train.main(args)
    rows = open(tmp_path / "curve.csv").read().splitlines()
    assert len(rows) == 11  # header + 10 updates of 64 samples
    assert (tmp_path / "questsim_policy.json").stat().st_size > 1e6 and (tmp_path / "curve.png").exists()
    train.main(args[:-4] + ["--samples", "1280", "--motions", ".", "--resume"])
    assert len(open(tmp_path / "curve.csv").read().splitlines()) == 21  # continued, not restarted
    dag = tmp_path / "dagger"
    train.main([d, "--out", str(dag), "--envs", "8", "--horizon", "8", "--samples", "640", "--motions", ".",
                "--bc-iters", "5"])
    assert len(open(dag / "curve.csv").read().splitlines()) == 11
    # The exported file loads in the run-time pipeline, and the evaluation reads it (untrained: falls).
    from . import evaluate
    out = tmp_path / "eval.json"
    evaluate.main([str(tmp_path / "questsim_policy.json"), d, "--motions", ".", "--json", str(out)])
    import json
    s = json.load(open(out))["summary"]
    assert s["clips"] == 3 and np.isfinite(s["mpjpe_cm"]) and s["mpjpe_cm"] > 0 and s["residual_N"] == 0
    assert s["mpjpe_cm"] <= s["mpjpe_output_cm"] + 5  # removing the latency does not make it much worse


@pytest.fixture(scope="module")
def clips30(clip_paths):
    return qe.load_clips(clip_paths, N3P_LOWER, 30.0)


def test_n3p_env_views_determinism_and_bad_input(clips30, clips):
    env = qe.N3PEnv(clips30, 4, 2)
    obs = env.obs
    assert obs.shape == (4, qe.N3PEnv.obs_size) == (4, 1008) and qe.N3PEnv.action_size == 48
    assert env.reward_terms.shape == (4, 6)
    before = obs.copy()
    env.step(np.zeros((4, 48), np.float32))
    assert not np.array_equal(before, obs) and np.all(np.isfinite(obs))
    assert np.all(env.reward >= 0) and np.all(env.reward <= 1.2 + 1e-6)
    a, b = qe.N3PEnv(clips30, 6, 3), qe.N3PEnv(clips30, 6, 3)
    rng = np.random.default_rng(1)
    for _ in range(30):
        u = (0.3 * rng.standard_normal((6, 48))).astype(np.float32)
        a.step(u, 1)
        b.step(u, 2)
        assert np.array_equal(a.obs, b.obs) and np.array_equal(a.reward, b.reward)
    with pytest.raises(ValueError, match=r"actions: expected float32 \[6, 48\]"):
        a.step(np.zeros((6, 47), np.float32))
    with pytest.raises(Exception, match="30 Hz"):
        qe.N3PEnv(clips, 2, 0)  # the QuestSim clips are at 36 Hz
    a.set_residual(0, 0)
    a.step(np.zeros((6, 48), np.float32))
    assert all(a.residual_force(i) == 0 for i in range(6))


def test_n3p_trainer_runs_resumes_and_exports(clip_paths, tmp_path):
    from . import train
    from ..format import read_weights
    d = os.path.dirname(clip_paths[0])
    args = [d, "--task", "n3p", "--out", str(tmp_path), "--envs", "8", "--horizon", "8", "--samples", "640",
            "--motions", ".", "--residual-force", "620", "--residual-torque", "250", "--residual-anneal", "1280"]
    train.main(args)
    assert len(open(tmp_path / "curve.csv").read().splitlines()) == 11
    doc, tensors, norm = read_weights(str(tmp_path / "n3p_correction_policy.json"))
    assert doc["kind"] == "n3p_correction_policy" and doc["meta"]["action_scale"] == 0.2
    assert tensors["layers.0.weight"].shape == (256, 1008) and tensors["layers.2.weight"].shape == (48, 256)
    assert norm["input_mean"].shape == (1008,)
    train.main(args[:9] + ["--samples", "1280"] + args[11:] + ["--resume"])
    rows = open(tmp_path / "curve.csv").read().splitlines()
    assert len(rows) == 21 and float(rows[-1].split(",")[11]) < 620  # continued; the residual bound annealed
    with pytest.raises(SystemExit, match="no DAgger"):
        train.main(args + ["--bc-iters", "2"])
    warm = tmp_path / "warm"  # a new run from the exported policy (its weights and statistics; a fresh critic)
    train.main([d, "--task", "n3p", "--out", str(warm), "--envs", "8", "--horizon", "8", "--samples", "1920", "--motions", ".",
                "--init-json", str(tmp_path / "n3p_correction_policy.json"), "--value-warmup", "2"])
    assert len(open(warm / "curve.csv").read().splitlines()) == 11  # from 1280 samples (the export's) to 1920
    with pytest.raises(SystemExit, match="expected a n3p_correction_policy"):
        train.main([d, "--task", "n3p", "--out", str(tmp_path / "bad"), "--envs", "8", "--horizon", "8", "--samples", "1920",
                    "--motions", ".", "--init-json", N3P_LOWER])


def test_reference_observations_and_frames(clips):
    """record_reference: at a reference-state start the reference observation equals the character's
    (forces aside); the frames move as the world model's algebra says (worldmodel.py), and the user
    window of step t re-expressed in the next heading frame is the next step's window."""
    import torch

    from . import worldmodel as wm
    cfg = qe.Config()
    assert not cfg.record_reference
    env = qe.Env(clips, [1.6, 1.75, 1.9, 1.8], 3, cfg)
    env.step(np.zeros((4, qe.Env.action_size), np.float32))
    assert not env.reference_obs.any() and not env.frames.any()  # off: nothing written
    cfg.record_reference = True
    env = qe.Env(clips, [1.6, 1.75, 1.9, 1.8], 3, cfg)
    ch = wm.CH - 6  # without the foot forces
    np.testing.assert_allclose(env.obs[:, :ch], env.reference_obs[:, :ch], atol=2e-5)
    np.testing.assert_allclose(env.frames[:, :4], env.frames[:, 4:], atol=1e-6)
    assert not env.reference_obs[:, ch:wm.CH].any()
    rng = np.random.default_rng(1)
    for _ in range(10):
        u, f0 = env.obs[:, wm.CH:-1].copy(), env.frames[:, :4].copy()
        env.step((0.05 * rng.standard_normal((4, qe.Env.action_size))).astype(np.float32))
        on = (env.terminated == 0) & (env.truncated == 0)
        f1 = env.frames[:, :4]
        d = wm.frame_delta(torch.from_numpy(f0), torch.from_numpy(f1))
        np.testing.assert_allclose(wm.frame_apply(torch.from_numpy(f0), d).numpy(), f1, atol=1e-5)
        ur = wm.reexpress_user(torch.from_numpy(u), torch.from_numpy(f0), torch.from_numpy(f1.copy())).numpy()
        np.testing.assert_allclose(ur.reshape(4, 7, 27)[on, 1:], env.obs[on, wm.CH:-1].reshape(-1, 7, 27)[:, :6], atol=1e-4)
        assert np.abs(env.frames[:, 2:4] - env.frames[:, 6:8]).max() < 1.0  # the reference stays near
        assert np.abs(env.obs[:, ch:wm.CH]).max() > 10 and not env.reference_obs[:, ch:wm.CH].any()


def test_predicted_references_load_as_training_clips(clip_paths, clips30, tmp_path):
    # Direct mode's predictions, written as the demo's BVH, load as the n3p environment's reference
    # clips under the clips' own names, with the clips' frame counts (one row per input frame).
    from . import predicted_references
    src = os.path.dirname(clip_paths[0])
    out = tmp_path / "pred"
    assert predicted_references.main([src, str(out), "--motions", "."]) == 0
    names = sorted(os.listdir(out))
    assert names == sorted(os.path.basename(p) for p in os.listdir(src) if p.endswith(".bvh"))
    pred = qe.load_clips([str(out / os.path.basename(p)) for p in clip_paths], N3P_LOWER, 30.0)
    for i in range(len(clip_paths)):
        assert abs(pred.frames(i) - clips30.frames(i)) <= 1, (clip_paths[i], pred.frames(i), clips30.frames(i))


def test_predicted_references_bad_input(tmp_path):
    # No matching clip, a bad --every and a malformed BVH each stop with one line naming the problem.
    from . import predicted_references
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(SystemExit, match="no training clips"):
        predicted_references.main([str(empty), str(tmp_path / "o1")])
    with pytest.raises(SystemExit, match="--every 0: expected a whole number >= 1"):
        predicted_references.main([str(empty), str(tmp_path / "o2"), "--every", "0"])
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "dataset-1_walk_bad_001.bvh").write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n")
    with pytest.raises(SystemExit, match="dataset-1_walk_bad_001.bvh"):
        predicted_references.main([str(bad), str(tmp_path / "o3")])
