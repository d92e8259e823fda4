"""Evaluation on the validation split (paper §8.5, Table 2; Figs. 6-7), predictor output as the C++
N3PPredictor produces it (start from the default state, no ground truth after the first frame):
  MPJPE full / upper / lower (cm): global joint positions of the FK pose vs the ground truth
       (upper = J_up, lower = J_lo)
  MPJRE (deg): global joint rotations
  jitter (km/s^3): mean norm of the third finite difference of joint positions times fps^3
  foot skating (cm/s): mean horizontal speed of a toe joint in frames where the ground truth says
       the foot is in contact
for 3-point input and HMD-only input (controllers replaced by o*, §8.2).
"""
import numpy as np
import torch

from ..lobstr.rotations import angle_between, from6d
from . import layout as L
from .model import initial_heading, rollout, world_pose


def run_clip(nets, c, init, hmd_only=False, dtype=torch.float64):
    """Per-frame world positions [F, 21, 3] and rotations [F, 21, 3, 3] for one clip (world arrays c)."""
    TP = torch.as_tensor(np.asarray(c["TP"]), dtype=dtype)[None]
    TQ6 = torch.as_tensor(np.asarray(c["TQ6"]), dtype=dtype)[None]
    glo0 = torch.tensor(init["g_lo"], dtype=dtype)[None]
    gup0 = torch.tensor(init["g_up"], dtype=dtype)[None]
    o0 = torch.tensor(init["o"], dtype=dtype)[None]
    h0 = initial_heading(TP[:, 0], TQ6[:, 0], o0)
    valid = None
    if hmd_only:
        valid = torch.ones(1, TP.shape[1], 3, dtype=torch.bool)
        valid[..., 1:] = False
    with torch.no_grad():
        out, _, _ = rollout(nets, TP, TQ6, h0, glo0, gup0, o0, valid)
        P, R = world_pose(out["h"][0], out["glo"][0], out["gup"][0])
    return P.numpy(), R.numpy(), out


def run_batch(nets, clips, init, hmd_only=False, dtype=torch.float64):
    """run_clip over several clips at once (padded with each clip's last frame; rows are independent)."""
    n = max(len(c["TP"]) for c in clips)
    pad = lambda a: np.concatenate([a, np.repeat(a[-1:], n - len(a), 0)]) if len(a) < n else a
    clip = {k: np.stack([pad(np.asarray(c[k])) for c in clips]) for k in ("TP", "TQ6")}
    B = len(clips)
    TP, TQ6 = torch.as_tensor(clip["TP"], dtype=dtype), torch.as_tensor(clip["TQ6"], dtype=dtype)
    rep = lambda v: torch.tensor(v, dtype=dtype)[None].repeat(B, 1)
    glo0, gup0, o0 = rep(init["g_lo"]), rep(init["g_up"]), rep(init["o"])
    h0 = initial_heading(TP[:, 0], TQ6[:, 0], o0)
    valid = None
    if hmd_only:
        valid = torch.ones(B, n, 3, dtype=torch.bool)
        valid[..., 1:] = False
    with torch.no_grad():
        out, _, _ = rollout(nets, TP, TQ6, h0, glo0, gup0, o0, valid)
        P, R = world_pose(out["h"], out["glo"], out["gup"])
    return [(P[b, :len(c["TP"])].numpy(), R[b, :len(c["TP"])].numpy()) for b, c in enumerate(clips)]


def metrics(nets, data, init, hmd_only=False, limit=None, batch=32):
    n = len(data.lens) if not limit else min(limit, len(data.lens))
    err, err_up, err_lo, rot, jit, skate = [], [], [], [], [], []
    toes = [L.NAMES.index("Toes_L"), L.NAMES.index("Toes_R")]
    order = sorted(range(n), key=lambda i: data.lens[i])
    results = {}
    for s in range(0, n, batch):
        idx = order[s:s + batch]
        for i, r in zip(idx, run_batch(nets, [data.clip(i) for i in idx], init, hmd_only)):
            results[i] = r
    for i in range(n):
        c = data.clip(i)
        P, R = results[i]
        G = c["P"].astype(np.float64)
        Rg = from6d(c["Q6"].astype(np.float64))
        e = np.linalg.norm(P - G, axis=-1)  # [F, 21]
        err.append(e.mean(1)), err_up.append(e[:, L.I_UP].mean(1)), err_lo.append(e[:, L.I_LO].mean(1))
        rot.append(angle_between(R, Rg).mean(1))
        if len(P) > 3:
            d3 = P[3:] - 3 * P[2:-1] + 3 * P[1:-2] - P[:-3]
            jit.append(np.linalg.norm(d3, axis=-1).mean(1) * L.FPS ** 3)
        v = np.linalg.norm(np.diff(P[:, toes][..., [0, 2]], axis=0), axis=-1) * L.FPS  # [F-1, 2]
        m = c["CT"][1:] > 0.5
        if m.any():
            skate.append(v[m])
    cat = lambda x: float(np.concatenate(x).mean()) if x else float("nan")  # nan: no such frames
    return {"clips": n, "mpjpe_cm": 100 * cat(err), "mpjpe_upper_cm": 100 * cat(err_up),
            "mpjpe_lower_cm": 100 * cat(err_lo), "mpjre_deg": cat(rot), "jitter_km_s3": cat(jit) / 1000,
            "foot_skating_cm_s": 100 * cat(skate)}


def report(nets, data, init, limit=None):
    out = {}
    for name, hmd in (("3-point", False), ("HMD-only", True)):
        m = metrics(nets, data, init, hmd, limit)
        out[name] = m
        print(f"{name:9s} ({m['clips']} clips): MPJPE {m['mpjpe_cm']:.2f} cm (upper {m['mpjpe_upper_cm']:.2f}, "
              f"lower {m['mpjpe_lower_cm']:.2f}), MPJRE {m['mpjre_deg']:.2f} deg, jitter {m['jitter_km_s3']:.2f} km/s^3, "
              f"foot skating {m['foot_skating_cm_s']:.2f} cm/s", flush=True)
    return out


def dump_for_direct_mode(data, path, limit=None):
    """Tracker input and ground truth of the clips as JSON for the C++ direct-mode evaluation
    (tests/n3p/eval_direct.cpp): per clip trackers p [F, 9], q6 [F, 18], joints [F, 63], contacts [F, 2].
    Stays outside the repository (it is made of the data)."""
    import json
    n = len(data.lens) if not limit else min(limit, len(data.lens))
    clips = []
    for i in range(n):
        c = data.clip(i)
        F = len(c["TP"])
        clips.append({"p": np.round(c["TP"].reshape(F, 9), 6).tolist(), "q6": np.round(c["TQ6"].reshape(F, 18), 6).tolist(),
                      "joints": np.round(c["P"].reshape(F, 63), 6).tolist(), "contacts": c["CT"].astype(int).tolist()})
    with open(path, "w") as f:
        json.dump({"upper": L.I_UP, "lower": L.I_LO, "toes": [L.NAMES.index("Toes_L"), L.NAMES.index("Toes_R")],
                   "clips": clips}, f)
