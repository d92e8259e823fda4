import json
import os
import subprocess
import sys

import numpy as np
import pytest
import torch

from weights_tool import golden, nets
from weights_tool.format import read_weights

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def test_golden_input_formula():
    x = golden.golden_input(3, 9)
    assert x.shape == (3, 9)
    assert x[2, 8] == pytest.approx(0.9 * np.sin(0.05 * 3 * (1 + 0.1 * 1) + 0.37 * 8), abs=1e-15)


def test_written_golden_reproduces_from_its_weights(tmp_path):
    _, x, y64, y32 = golden.write_golden("g", lambda: nets.LoBSTrNet(hidden=12, latent=6), "lobstr", tmp_path,
                                         steps=50, sample_every=7, normalize=True)
    doc, tensors, norm = read_weights(tmp_path / "g.weights.json")
    m = nets.LoBSTrNet(hidden=12, latent=6).double().eval()
    m.load_state_dict({k: torch.from_numpy(v) for k, v in tensors.items()})
    xin = (x - norm["input_mean"]) / norm["input_std"]
    with torch.no_grad():
        y, _ = m(torch.from_numpy(xin)[None])
    y = y[0].numpy() * norm["output_std"] + norm["output_mean"]
    g = json.loads((tmp_path / "g.golden.json").read_text())
    assert g["sample_steps"] == [0, 7, 14, 21, 28, 35, 42, 49]
    from weights_tool.format import decode_tensor
    np.testing.assert_allclose(decode_tensor(g["output_f64"]), y[g["sample_steps"]], atol=1e-12)
    assert np.abs(y64 - y32).max() < 1e-4  # float32 run is close but not identical
    assert np.abs(y64 - y32).max() > 0


def test_committed_goldens_are_current(tmp_path):
    """tests/golden must be what `weights_tool golden small` writes (regenerate if models change)."""
    golden.write_set("small", tmp_path)
    committed = os.path.join(ROOT, "tests", "golden")
    from weights_tool.format import decode_tensor
    for name in golden.SMALL:
        a = json.loads((tmp_path / (name + ".weights.json")).read_text())
        b = json.load(open(os.path.join(committed, name + ".weights.json")))
        assert a == b, f"{name}.weights.json differs from a fresh generation"
        # outputs may differ in the last bits with the BLAS kernel of this CPU
        a = json.loads((tmp_path / (name + ".golden.json")).read_text())
        b = json.load(open(os.path.join(committed, name + ".golden.json")))
        assert a["sample_steps"] == b["sample_steps"]
        np.testing.assert_allclose(decode_tensor(a["output_f64"]), decode_tensor(b["output_f64"]), atol=1e-12)
        np.testing.assert_allclose(decode_tensor(a["output_f32"]), decode_tensor(b["output_f32"]), atol=2e-6)


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "weights_tool", *args], cwd=ROOT, capture_output=True, text=True)


def test_export_cli_from_checkpoint(tmp_path):
    m = nets.LoBSTrNet(hidden=16, latent=8)
    ck = tmp_path / "ck.pt"
    torch.save({"state_dict": m.state_dict(), "meta": {"frame_rate": 60},
                "normalization": {"input_mean": torch.zeros(37), "input_std": torch.ones(37)}}, ck)
    r = run_cli("export", str(ck), str(tmp_path / "out.json"), "--kind", "lobstr", "--hidden", "16", "--latent", "8")
    assert r.returncode == 0, r.stderr
    doc, tensors, norm = read_weights(tmp_path / "out.json")
    assert doc["meta"] == {"input_size": 37, "output_size": 52, "frame_rate": 60}
    np.testing.assert_array_equal(tensors["gru.weight_hh_l0"], m.gru.weight_hh_l0.detach().numpy())
    assert set(norm) == {"input_mean", "input_std"}


def test_export_cli_refuses_a_mismatched_checkpoint(tmp_path):
    m = nets.LoBSTrNet(hidden=16, latent=8)
    ck = tmp_path / "ck.pt"
    torch.save(m.state_dict(), ck)
    r = run_cli("export", str(ck), str(tmp_path / "out.json"), "--kind", "lobstr", "--hidden", "32")
    assert r.returncode != 0 and "size mismatch" in r.stderr
    assert not (tmp_path / "out.json").exists()
