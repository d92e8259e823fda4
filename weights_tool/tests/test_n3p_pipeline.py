"""Neural3Points Python side: heading-frame algebra, dataset from a BVH (synthetic motion on the standard
skeleton, written here), a few training iterations of every stage on tiny data, export / reload,
evaluation, and the committed C++ parity golden being what the reference computes today."""
import json
import math
import os

import numpy as np
import pytest
import torch

from weights_tool.lobstr.standard import STANDARD
from weights_tool.n3p import dataset, evaluate, export, golden, layout as L, train, weights
from weights_tool.n3p.model import Sub, rollout, targets

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_heading_algebra():
    g = torch.Generator().manual_seed(0)
    a = torch.rand(100, 3, generator=g, dtype=torch.float64) * 6 - 3
    b = torch.rand(100, 3, generator=g, dtype=torch.float64) * 6 - 3
    d = L.delta(a, b)
    back = L.compose(a, d)
    assert torch.allclose(back[:, :2], b[:, :2], atol=1e-12)
    assert torch.allclose(L.wrap(back[:, 2] - b[:, 2]), torch.zeros(100, dtype=torch.float64), atol=1e-12)
    p = torch.rand(100, 4, 3, generator=g, dtype=torch.float64)
    assert torch.allclose(L.point(a, L.point_inv(a, p)), p, atol=1e-12)
    # R_y(theta) maps +Z to (sin, 0, cos)
    z = L.rot(torch.tensor([0.0, 0.0, 0.7]), torch.tensor([[0.0, 0.0, 1.0]]))
    assert torch.allclose(z, torch.tensor([[math.sin(0.7), 0.0, math.cos(0.7)]]), atol=1e-7)
    # composition: (a x b) applied to p == a applied to (b applied to p)
    ab = L.compose(a, b)
    assert torch.allclose(L.point(ab, p), L.point(a, L.point(b, p)), atol=1e-10)


def write_bvh(path, frames=90):
    """The standard skeleton walking a slow curve with swinging limbs (cm, 30 fps, ZXY)."""
    S = STANDARD
    n = len(S["names"])
    children = {i: [j for j in range(n) if S["parents"][j] == i] for i in range(n)}
    lines = ["HIERARCHY"]

    def emit(j, depth):
        ind = "  " * depth
        lines.append(f"{ind}{'ROOT' if depth == 0 else 'JOINT'} {S['names'][j]}")
        lines.append(ind + "{")
        o = [100 * v for v in S["offsets"][j]]
        lines.append(f"{ind}  OFFSET {o[0]:.4f} {o[1]:.4f} {o[2]:.4f}")
        ch = "Xposition Yposition Zposition " if depth == 0 else ""
        lines.append(f"{ind}  CHANNELS {6 if depth == 0 else 3} {ch}Zrotation Xrotation Yrotation")
        for c in children[j]:
            emit(c, depth + 1)
        if not children[j]:
            lines.extend([ind + "  End Site", ind + "  {", ind + "    OFFSET 0 5 0", ind + "  }"])
        lines.append(ind + "}")

    emit(0, 0)
    lines += ["MOTION", f"Frames: {frames}", "Frame Time: 0.0333333"]
    for t in range(frames):
        s = math.sin(2 * math.pi * t / 30)
        vals = [100 * 0.01 * t, 90.0, 100 * 0.005 * t * t / frames]
        for j in range(n):
            # root: stand upright (the standard skeleton's bones run along local X) and turn slowly
            if j == 0:
                vals += [90.0, 0.0, 20.0 * t / frames]
            else:
                vals += [5.0 * s * (1 + j % 3), 3.0 * s, 2.0 * s]
        lines.append(" ".join(f"{v:.4f}" for v in vals))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    d = tmp_path_factory.mktemp("n3p")
    for i in range(3):
        write_bvh(str(d / f"clip{i}.bvh"), 80 + 10 * i)
    dataset.build(str(d), str(d / "data.npz"))
    return d, dataset.Data(str(d / "data.npz"))


def test_dataset_arrays(tiny):
    _, data = tiny
    assert len(data.lens) == 3
    c = data.clip(0)
    assert c["P"].shape[1:] == (21, 3) and c["TP"].shape[1:] == (3, 3) and c["H"].shape[1] == 3
    for k in dataset.KEYS:
        assert np.all(np.isfinite(c[k])), k
    # trackers are the head / hand joints; heading sits under the hips
    assert np.allclose(c["TP"][:, 0], c["P"][:, L.NAMES.index("Head")], atol=1e-5)
    assert np.allclose(c["H"][:, 0], c["P"][:, 0, 0], atol=1e-5)
    # feature sizes match the layouts
    A = {k: torch.from_numpy(c[k][:10])[None] for k in dataset.KEYS}
    F = targets(A, A["H"])
    assert F["sig_in"].shape[-1] == L.SIG_IN and F["glo"].shape[-1] == L.N_GLO and F["gup"].shape[-1] == L.N_GUP
    assert F["onext"].shape[-1] == L.N_O and F["z"].shape[-1] == L.N_Z
    # FK residual of the ground truth is ~0 (positions and orientations agree)
    assert float(L.fk_residual(F["gup"], L.J_UP).abs().max()) < 1e-4
    assert float(L.fk_residual(F["glo"], L.J_LO).abs().max()) < 1e-4


def test_training_stages_export_and_evaluate(tiny, tmp_path):
    d, data = tiny
    torch.manual_seed(0)
    rng = np.random.default_rng(0)
    nets = [Sub(n, h) for n, h in zip(("sig", "lo", "up"), (8, 12, 12))]
    train.set_normalization(nets, data, rng)
    T = 8
    for sub in nets:
        opt = torch.optim.Adam(sub.parameters(), lr=5e-4)
        before = None
        for _ in range(2):
            loss, _ = train.pretrain_step(sub, train.batch(data, rng, 4, T + 3), T)
            assert torch.isfinite(loss)
            opt.zero_grad()
            loss.backward()
            opt.step()
            before = before or loss.item()
    for p in nets[2].parameters():
        p.requires_grad_(False)
    w_up = [p.clone() for p in nets[2].parameters()]
    opt = torch.optim.Adam(list(nets[0].parameters()) + list(nets[1].parameters()), lr=5e-4)
    loss, parts = train.finetune_step(nets, train.batch(data, rng, 4, T + 3), T)
    assert torch.isfinite(loss) and set(parts) == {"h", "sig", "lo", "up"}
    opt.zero_grad()
    loss.backward()
    opt.step()
    assert all(torch.equal(a, b) for a, b in zip(w_up, nets[2].parameters()))  # G_up frozen
    assert nets[0].net.encoder.weight.grad is not None and nets[1].net.encoder.weight.grad is not None
    for s in nets:
        s.eval()
    init = export.initial_state(data)
    prefix = str(tmp_path / "n3p")
    paths = export.export_nets(nets, prefix, init, {"note": "test"})
    doc = json.load(open(paths[1]))
    assert doc["kind"] == "n3p_lower" and doc["meta"]["credit"].startswith("Bandai Namco")
    assert doc["meta"]["lower_body_joints"] == L.J_LO and len(doc["meta"]["initial_state"]["g_lo"]) == L.N_GLO
    back, init2 = weights.load(prefix)
    c = data.clip(0)
    P1, _, _ = evaluate.run_clip(nets, c, init)
    P2, _, _ = evaluate.run_clip(back, c, init2)
    assert np.allclose(P1, P2, atol=1e-5)
    for hmd in (False, True):
        m = evaluate.metrics(back, data, init2, hmd_only=hmd)
        assert all(np.isfinite(v) for k, v in m.items() if k != "foot_skating_cm_s")  # no contacts here
        assert m["mpjpe_cm"] > 0


def test_hmd_only_uses_ostar():
    nets, init = golden.small_nets()
    TP, TQ6 = golden.cmu_trackers(frames=20)
    tp, tq = torch.tensor(TP)[None], torch.tensor(TQ6)[None]
    h0 = torch.zeros(1, 3, dtype=torch.float64)
    args = (h0, torch.tensor(init["g_lo"], dtype=torch.float64)[None], torch.tensor(init["g_up"], dtype=torch.float64)[None],
            torch.tensor(init["o"], dtype=torch.float64)[None])
    with torch.no_grad():
        a, _, _ = rollout(nets, tp, tq, *args)
        valid = torch.ones(1, 20, 3, dtype=torch.bool)
        valid[..., 1:] = False
        b, _, _ = rollout(nets, tp, tq, *args, valid=valid)
        moved = tp.clone()
        moved[:, :, 1:] += 5.0  # the controllers' values must not matter when they are missing
        c, _, _ = rollout(nets, moved, tq, *args, valid=valid)
    assert not torch.allclose(a["gup"], b["gup"])
    assert torch.equal(b["gup"], c["gup"])


def test_committed_golden_matches_reference(tmp_path):
    golden.write(str(tmp_path))
    new = json.load(open(tmp_path / "n3p_small.golden.json"))
    old = json.load(open(os.path.join(ROOT, "tests", "n3p", "golden", "n3p_small.golden.json")))
    for k in ("h", "z", "o_star", "g_lo", "g_up", "positions", "trackers_p"):
        assert np.allclose(np.array(new[k]), np.array(old[k]), atol=1e-6), k
