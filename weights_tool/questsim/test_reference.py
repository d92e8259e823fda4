"""pytest for the QuestSim reference (run by CTest as questsim_pytest, from the repository root)."""
import math

import numpy as np
import pytest
import torch

from weights_tool.questsim import layout, observation, policy


def test_layout_paper_numbers():
    # §3.3: 16 links, 33 DoF -> o_sim in R^312; §3.5: 6 frames -> 162; plus the height.
    L = layout.layout(16, 33, 5)
    assert L["user"] == 312
    assert L["height"] - L["user"] == 162
    assert L["size"] == 475
    assert layout.size(21, 48, 6) == 607  # default avatar, current + 6 future frames


def _chain():
    return {"bodies": [
        {"name": "Hips", "parent": None, "joint": "free", "pos": [0, 1, 0]},
        {"name": "Leg", "parent": "Hips", "joint": "revolute", "axis": [1, 0, 0], "pos": [0, -0.5, 0]},
        {"name": "Foot_L", "parent": "Leg", "joint": "spherical", "pos": [0, -0.4, 0]},
        {"name": "Foot_R", "parent": "Hips", "joint": "spherical", "pos": [0.1, -0.9, 0]},
    ]}


def test_fk_revolute_chain_analytic():
    # Root at (1, 1, 2) turned 90 deg about Y, knee (axis x) bent by a: in the root frame the foot is at
    # (0, -0.5 - 0.4 cos a, -0.4 sin a).
    a = 0.7
    c, s = math.cos(math.pi / 4), math.sin(math.pi / 4)
    q = [1, 1, 2, c, 0, s, 0, a, 1, 0, 0, 0, 1, 0, 0, 0]
    v = [0.0] * 6 + [2.0] + [0.0] * 6
    R, p, w, vl = observation.forward_kinematics(_chain(), torch.tensor(q, dtype=torch.float64),
                                                 torch.tensor(v, dtype=torch.float64))
    Ry = torch.tensor([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=torch.float64)
    local = torch.tensor([0, -0.5 - 0.4 * math.cos(a), -0.4 * math.sin(a)], dtype=torch.float64)
    assert torch.allclose(p[2], torch.tensor([1.0, 1.0, 2.0], dtype=torch.float64) + Ry @ local, atol=1e-12)
    # Knee rate 2 rad/s about the root's x axis (world: Ry e_x = -z); the foot origin moves at w x r.
    assert torch.allclose(w[2], Ry @ torch.tensor([2.0, 0, 0], dtype=torch.float64), atol=1e-12)
    assert torch.allclose(vl[2], torch.linalg.cross(w[1], p[2] - p[1]), atol=1e-12)


def test_observation_heading_invariance():
    rng = np.random.default_rng(0)
    model = _chain()
    q = np.array([0.3, 0.9, -0.2, 1, 0, 0, 0, 0.4, 1, 0, 0, 0, 1, 0, 0, 0], dtype=np.float64)
    r = rng.normal(size=4); r /= np.linalg.norm(r)
    q[3:7] = r
    v = rng.normal(size=13)
    user = [[list(rng.normal(size=3)) + list(x / np.linalg.norm(x)) for x in rng.normal(size=(3, 4))]
            for _ in range(7)]
    contacts = [[2, 10.0, 300.0, -5.0], [3, -3.0, 200.0, 1.0]]
    o1 = observation.observation(model, q, v, contacts, user, 1.7)
    # Rotate and shift the whole scene about Y.
    psi, t = 1.1, np.array([2.0, 0.0, -1.0])
    G = np.array([[math.cos(psi), 0, math.sin(psi)], [0, 1, 0], [-math.sin(psi), 0, math.cos(psi)]])
    gq = np.array([math.cos(psi / 2), 0, math.sin(psi / 2), 0])

    def qmul(a, b):
        w1, x1, y1, z1 = a
        w2, x2, y2, z2 = b
        return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                         w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])

    q2 = q.copy()
    q2[0:3] = G @ q[0:3] + t
    q2[3:7] = qmul(gq, q[3:7])
    user2 = [[list(G @ np.array(e[0:3]) + t) + list(qmul(gq, np.array(e[3:7]))) for e in fr] for fr in user]
    contacts2 = [[c[0], *(G @ np.array(c[1:4]))] for c in contacts]
    o2 = observation.observation(model, q2, v, contacts2, user2, 1.7)
    assert torch.allclose(o1, o2, atol=1e-10)
    L = layout.layout(4, 7, 6)
    assert o1.shape[0] == L["size"]
    assert float(o1[L["height"]]) == 1.7


def test_policy_file_roundtrip(tmp_path):
    path = tmp_path / "p.json"
    policy.write_policy(str(path), 4, 7, 6, seed=3, output_gain=1.0)
    model, norm = policy.load_policy(str(path))
    x = np.linspace(-1, 1, layout.size(4, 7, 6))
    y64 = policy.run_policy(model, norm, x, torch.float64)
    y32 = policy.run_policy(model, norm, x, torch.float32)
    assert y64.shape == (7,)
    assert np.max(np.abs(y64)) <= 1.0
    assert np.max(np.abs(y64 - y32)) < 1e-5


def test_trainer_starts_from_an_exported_policy(tmp_path):
    # train.export -> train.init_from_json gives back the actor's weights (float32) and the
    # observation statistics the export normalises with; a policy of another shape is refused.
    from weights_tool.questsim import train
    torch.manual_seed(3)
    n_obs, n_act = 607, 48
    src = train.ActorCritic(n_obs, n_act, 0.05)
    with torch.no_grad():
        for p in src.actor.parameters():
            p.normal_(0, 0.1)
    stats = train.RunningStats(n_obs)
    stats.update(np.random.default_rng(1).normal(2.0, 3.0, (500, n_obs)))
    path = str(tmp_path / "policy.json")
    train.export(path, src, stats, n_obs, n_act, {"samples": 12345, "iterations": 7})
    dst = train.ActorCritic(n_obs, n_act, 0.05)
    got = train.RunningStats(n_obs)
    it, samples = train.init_from_json(path, dst, got, n_obs, n_act)
    assert (it, samples) == (7, 12345)
    for a, b in zip(src.actor.parameters(), dst.actor.parameters()):
        assert torch.equal(a, b)
    x = torch.randn(4, n_obs)
    assert torch.equal(src.actor(x)[0], dst.actor(x)[0])
    want_std = stats.std(0.05).astype(np.float32)
    want_mean = stats.mean.astype(np.float32)
    want_mean[-1], want_std[-1] = 1.75, 1.0  # the export's fixed height feature
    assert np.allclose(got.mean, want_mean, rtol=1e-6, atol=1e-6)
    assert np.allclose(got.std(0.05), want_std, rtol=1e-5)
    with pytest.raises(SystemExit, match="expected a questsim_policy 600 -> 48"):
        train.init_from_json(path, train.ActorCritic(600, n_act, 0.05), train.RunningStats(600), 600, n_act)


def test_world_model_policy_loader_checks_kind_and_size(tmp_path):
    # worldmodel.load_policy reads the shipped policy's tensors and refuses any other kind or shape
    # with the trainer's one-line message (it used to load whatever tensors a file held).
    from weights_tool.questsim import train, worldmodel
    n_obs, n_act = worldmodel.L["size"], worldmodel.NA
    src = train.ActorCritic(n_obs, n_act, 0.05)
    stats = train.RunningStats(n_obs)
    stats.update(np.random.default_rng(2).normal(0.0, 1.0, (50, n_obs)))
    good = str(tmp_path / "good.json")
    train.export(good, src, stats, n_obs, n_act, {"samples": 1, "iterations": 1})
    m, _, doc = worldmodel.load_policy(good)
    assert doc["kind"] == "questsim_policy"
    for a, b in zip(src.actor.parameters(), m.parameters()):
        assert torch.equal(a, b)
    other = str(tmp_path / "n3p.json")
    small = train.ActorCritic(1008, n_act, 0.05, train.N3P_HIDDEN, "n3p_correction_policy")
    train.export_n3p(other, small, train.RunningStats(1008), 1008, n_act, {"samples": 1})
    with pytest.raises(SystemExit, match=f"n3p.json: expected a questsim_policy {n_obs} -> {n_act}, found n3p_correction_policy 1008"):
        worldmodel.load_policy(other)


def test_pipeline_evals_parser_reads_both_log_formats(tmp_path):
    # plot_pipeline_evals reads the snapshot loops' lines (the older short form and the full
    # n3p_physics_eval summary) and skips anything else.
    from weights_tool.questsim import plot_pipeline_evals as pe
    f = tmp_path / "evals.txt"
    f.write_text("0142 samples 3276800 half 1 physics  MPJPE  21.49 cm ; 30.90 per minute of output\n"
                 "a line to skip\n"
                 "samples 1843200 half 0 physics  MPJPE  23.91 cm (upper 1, lower 2) | foot skating  49.48 cm/s | "
                 "falls 314 (height 175, tilt 71, diverged 68; 28.72 per minute of output), failed steps 2\n"
                 "samples 1000 half 0 physics  MPJPE  30.00 cm ; 40.00 per minute of output\n")
    got = pe.read_evals(str(f))
    assert got == {0: [(1000, 40.0, 30.0), (1843200, 28.72, 23.91)], 1: [(3276800, 30.9, 21.49)]}
    png = tmp_path / "p.png"
    assert pe.main([str(png), str(f), "--labels", "run", "--baseline", "26.6"]) == 0 and png.stat().st_size > 0
