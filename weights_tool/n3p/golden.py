"""Parity golden for the C++ predictor test (tests/n3p): small random sub-predictors (hidden sizes 16,
24, 24) run through the Eq. (2) rollout over a whole clip of CMU motion
(/usr/share/assimp/models/BVH/01_01.bvh, resampled to 30 fps; never Bandai data), geometry in float64
and networks in float32 as in C++. Frames 60-119 run HMD-only and frames 150-179 without the left
controller (o* stands in, §8.2).

Writes <dir>/n3p_small{_signal,_lower,_upper}.json and <dir>/n3p_small.golden.json with, per frame,
the input trackers (p, 6D, present flags) and the outputs: h, z~, g_lo, g_up, o*, FK joint positions.
"""
import json
import os

import numpy as np
import torch

from ..lobstr.skeleton import Clip
from . import layout as L
from .dataset import tracker_arrays
from .export import export_nets
from .model import Sub, initial_heading, rollout, world_pose

CMU = "/usr/share/assimp/models/BVH/01_01.bvh"
HIDDEN = (16, 24, 24)
STATE_EVERY = 4  # g_lo, g_up stored every 4th frame (file size)


def small_nets(seed=0):
    torch.manual_seed(seed)
    nets = [Sub(n, h) for n, h in zip(("sig", "lo", "up"), HIDDEN)]
    g = torch.Generator().manual_seed(seed + 1)
    for s in nets:
        s.eval()
        s.in_mean.copy_(0.1 * torch.randn(s.in_mean.shape, generator=g))
        s.in_std.copy_(0.5 + torch.rand(s.in_std.shape, generator=g))
        s.out_mean.copy_(0.05 * torch.randn(s.out_mean.shape, generator=g))
        s.out_std.copy_(0.05 + 0.1 * torch.rand(s.out_std.shape, generator=g))
    # a plausible start state: identity rotations, joints at their rest heights
    glo = [0.0] * L.N_GLO
    gup = [0.0] * L.N_GUP
    for k, n in ((len(L.J_LO), glo), (len(L.J_UP), gup)):
        for j in range(k):
            n[6 * k + 6 * j + 2], n[6 * k + 6 * j + 4] = 1.0, 1.0
            n[3 * j + 1] = 0.9
    o = [0.0, 1.4, 0.0, 0.2, 1.0, 0.0, -0.2, 1.0, 0.0] + [0.0, 0.0, 1.0, 0.0, 1.0, 0.0] * 3
    return nets, {"g_lo": glo, "g_up": gup, "o": o}


def cmu_trackers(path=CMU, frames=200, step=4):
    clip = Clip(path)
    TP, TQ6, _, _ = tracker_arrays(clip)
    return TP[::step][:frames], TQ6[::step][:frames]


def _rollout_fields(nets, init, TP, TQ6, present):
    """The golden fields of an autoregressive float64 rollout (Eq. 2) over trackers TP/TQ6 with the
    per-frame controller presence `present`, starting from the default state `init`."""
    F = len(TP)
    d = torch.float64
    tp, tq = torch.tensor(TP, dtype=d)[None], torch.tensor(TQ6, dtype=d)[None]
    o0 = torch.tensor(init["o"], dtype=d)[None]
    h0 = initial_heading(tp[:, 0], tq[:, 0], o0)
    with torch.no_grad():
        out, _, _ = rollout(nets, tp, tq, h0, torch.tensor(init["g_lo"], dtype=d)[None],
                            torch.tensor(init["g_up"], dtype=d)[None], o0, torch.tensor(present)[None])
        P, _ = world_pose(out["h"][0], out["glo"][0], out["gup"][0])
    r = lambda a: np.round(np.asarray(a, dtype=np.float64), 9).tolist()
    return {"frames": F, "state_every": STATE_EVERY,
            "trackers_p": TP.reshape(F, 9).tolist(), "trackers_q6": TQ6.reshape(F, 18).tolist(),
            "present": present.astype(int).tolist(),
            "h": r(out["h"][0]), "z": r(out["z"][0]), "o_star": r(out["ostar"][0]),
            "g_lo": r(out["glo"][0][::STATE_EVERY]), "g_up": r(out["gup"][0][::STATE_EVERY]),
            "positions": r(P.reshape(F, -1))}


def write(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    nets, init = small_nets()
    prefix = os.path.join(out_dir, "n3p_small")
    export_nets(nets, prefix, init, training={"note": "random weights for the parity test"}, trained_on_bandai=False)
    TP, TQ6 = cmu_trackers()
    present = np.ones((len(TP), 3), bool)
    present[60:120, 1:] = False
    present[150:180, 1] = False
    g = {"source": "CMU 01_01 (resampled to 30 fps), random small sub-predictors; weights_tool.n3p golden",
         "hidden": list(HIDDEN)}
    g.update(_rollout_fields(nets, init, TP, TQ6, present))
    with open(prefix + ".golden.json", "w") as f:
        json.dump(g, f, separators=(",", ":"))
    return prefix


def write_default(prefix, out_path, frames=100):
    """Golden of the default (trained, paper-size) weights at `prefix` over CMU 01_01: 3-point, then
    HMD-only for frames 40-69. Same fields as write(). Regenerate whenever the default weights change."""
    from .weights import load
    nets, init = load(prefix)
    TP, TQ6 = cmu_trackers(frames=frames)
    present = np.ones((len(TP), 3), bool)
    present[40:70, 1:] = False
    g = {"source": f"CMU 01_01 (resampled to 30 fps), default weights {os.path.basename(prefix)}_*.json; "
                   "weights_tool.n3p golden --default"}
    g.update(_rollout_fields(nets, init, TP, TQ6, present))
    with open(out_path, "w") as f:
        json.dump(g, f, separators=(",", ":"))
    return out_path
