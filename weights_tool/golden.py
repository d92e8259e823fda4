"""Golden input/output vectors for the C++ parity tests.

For a reference module with random weights, writes <name>.weights.json (the weights, exactly as
`export` writes them) and <name>.golden.json: the outputs of a stateful run over `steps` frames, in
float64 and float32, sampled every `sample_every` frames (and at the last frame) to keep files small.
The input sequence is not stored: both sides compute it with `golden_input` (same formula in
tests/nn/golden.hpp). Weights are rounded to float32 first, so float and double runs use the same values.
"""
import json
import math
import os

import numpy as np
import torch

from . import nets
from .format import encode_tensor, write_weights


def golden_input(steps, size):
    """x[t, i] = 0.9 sin(0.05 (t + 1) (1 + 0.1 (i mod 7)) + 0.37 i), float64."""
    t = np.arange(steps, dtype=np.float64)[:, None]
    i = np.arange(size, dtype=np.float64)[None, :]
    return 0.9 * np.sin(0.05 * (t + 1.0) * (1.0 + 0.1 * np.mod(i, 7)) + 0.37 * i)


# name -> (factory, kind). "small" models are committed under tests/golden; "paper" ones are
# generated at test time (they are megabytes) by the PyTorch -> export -> C++ chain test.
SMALL = {
    "zoo": (lambda: nets.LayerZoo(), "sequential"),
    "gru_stack": (lambda: nets.GRUStack(11, 23, 2), "gru"),
    "lobstr_small": (lambda: nets.LoBSTrNet(hidden=40, latent=24), "lobstr"),
    "n3p_small": (lambda: nets.N3PPredictor(45, 20, 13, kind="n3p_signal"), "n3p_signal"),
    "policy_small": (lambda: nets.MLPPolicy([50, 32, 32, 9], "relu", "identity", "n3p_policy"), "n3p_policy"),
    "mlp_tanh_small": (lambda: nets.MLPPolicy([20, 16, 12, 8, 5], "tanh", "tanh", "mlp"), "mlp"),
}
# Sizes used by the papers (see the core issue and bench/): N3P inputs/outputs as in bench/bench_networks.cpp.
PAPER = {
    "lobstr_1024": (lambda: nets.LoBSTrNet(hidden=1024, latent=128), "lobstr"),
    "lobstr_256": (lambda: nets.LoBSTrNet(hidden=256, latent=128), "lobstr"),
    "n3p_signal": (lambda: nets.N3PPredictor(45, 64, 12, kind="n3p_signal"), "n3p_signal"),
    "n3p_lower": (lambda: nets.N3PPredictor(12, 128, 113, kind="n3p_lower"), "n3p_lower"),
    "n3p_upper": (lambda: nets.N3PPredictor(45, 128, 201, kind="n3p_upper"), "n3p_upper"),
    "n3p_policy": (lambda: nets.MLPPolicy([868, 256, 256, 72], "relu", "identity", "n3p_policy"), "n3p_policy"),
    "questsim_policy": (lambda: nets.MLPPolicy([475, 400, 300, 200, 33], "tanh", "tanh", "questsim_policy"),
                        "questsim_policy"),
}


def make_model(factory, seed):
    torch.manual_seed(seed)
    m = factory().eval()
    with torch.no_grad():  # non-trivial biases, and weights exactly representable in float32
        for p in m.parameters():
            p.add_(0.05 * torch.randn_like(p))
            p.copy_(p.float())
    return m


def run_sequence(model, x, dtype):
    m = model.to(dtype)
    with torch.no_grad():
        y, _ = m(torch.from_numpy(x).to(dtype)[None])
    return y[0].double().numpy()


def write_golden(name, factory, kind, out_dir, steps=1000, sample_every=10, seed=1234, normalize=False):
    model = make_model(factory, seed)
    x = golden_input(steps, model.inputs)
    norm = None
    if normalize:  # exercise the normalisation path: C++ applies it around the network
        rng = np.random.default_rng(seed)
        norm = {"input_mean": rng.normal(0, 0.2, model.inputs).astype(np.float32),
                "input_std": rng.uniform(0.5, 2.0, model.inputs).astype(np.float32),
                "output_mean": rng.normal(0, 0.2, model.outputs).astype(np.float32),
                "output_std": rng.uniform(0.5, 2.0, model.outputs).astype(np.float32)}
    xin = x if norm is None else (x - norm["input_mean"].astype(np.float64)) / norm["input_std"].astype(np.float64)
    y64 = run_sequence(model, xin, torch.float64)
    y32 = run_sequence(model, xin.astype(np.float32).astype(np.float64), torch.float32)
    if norm is not None:
        y64 = y64 * norm["output_std"].astype(np.float64) + norm["output_mean"].astype(np.float64)
        y32 = y32 * norm["output_std"].astype(np.float64) + norm["output_mean"].astype(np.float64)
    samples = sorted(set(range(0, steps, sample_every)) | {steps - 1})
    os.makedirs(out_dir, exist_ok=True)
    write_weights(os.path.join(out_dir, f"{name}.weights.json"), nets.export_state_dict(model.float()), kind,
                  model.inputs, model.outputs, meta={"frame_rate": 30, "note": "random weights for parity tests"},
                  normalization=norm)
    golden = {"format": "sparsebody-golden", "version": 1, "name": name, "kind": kind, "steps": steps,
              "input": "sin-v1", "input_size": model.inputs, "output_size": model.outputs,
              "sample_steps": samples,
              "output_f64": encode_tensor(y64[samples], "float64"),
              "output_f32": encode_tensor(y32[samples], "float64")}
    with open(os.path.join(out_dir, f"{name}.golden.json"), "w") as f:
        json.dump(golden, f, separators=(",", ":"))
    return model, x, y64, y32


def write_set(which, out_dir, steps=1000):
    specs = {"small": SMALL, "paper": PAPER}[which]
    for i, (name, (factory, kind)) in enumerate(specs.items()):
        write_golden(name, factory, kind, out_dir, steps=steps, seed=1000 + i, normalize=(name == "lobstr_small"))
    return list(specs)
