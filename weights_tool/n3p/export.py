"""Checkpoint -> three sparsebody weights files <prefix>_signal.json, <prefix>_lower.json,
<prefix>_upper.json (kinds n3p_signal, n3p_lower, n3p_upper) with the pipeline metadata in meta:
skeleton, joint sets, layouts, 6D layout, frame rate, the default start state, credit / licence.
"""
import numpy as np
import torch

from ..format import write_weights
from ..lobstr.export import add_provenance
from ..lobstr.standard import STANDARD
from . import layout as L
from .dataset import KEYS
from .model import targets

NORM_NAMES = {"in_mean": "input_mean", "in_std": "input_std", "out_mean": "output_mean", "out_std": "output_std"}
SUFFIX = {"sig": "_signal.json", "lo": "_lower.json", "up": "_upper.json"}


def initial_state(data):
    """Default start state: the mean over clips of the ground-truth g_lo, g_up and o at each clip's
    second frame (clips start standing), in its own heading frame. Values rounded to float32."""
    glo, gup, o = [], [], []
    for i in range(len(data.lens)):
        c = data.clip(i)
        A = {k: torch.from_numpy(np.asarray(c[k][:3], dtype=np.float64))[None] for k in KEYS}
        F = targets(A, A["H"])
        glo.append(F["glo"][0, 0].numpy()), gup.append(F["gup"][0, 0].numpy()), o.append(F["up_in"][0, 0].numpy())
    r = lambda v: [float(x) for x in np.mean(v, 0).astype(np.float32)]
    g = r(glo)
    for k in range(L.Z_IN_GLO + 3, L.N_GLO):  # z's velocity, momentum and dh: at rest
        g[k] = 0.0
    return {"g_lo": g, "g_up": r(gup), "o": r(o)}


def meta(init, hidden, training=None, trained_on_bandai=True):
    m = {
        "frame_rate": L.FPS,
        "rotation": {"representation": "6d", "layout": "columns", "columns": [2, 1]},
        "skeleton": {k: STANDARD[k] for k in ("names", "parents", "offsets")},
        "lower_body_joints": L.J_LO,
        "upper_body_joints": L.J_UP,
        "tracker_joints": L.TRACKERS,
        "layout": {
            "o": "[p_H p_L p_R (9) | q6_H q6_L q6_R (18)] in a heading frame",
            "z": "[p_up (3) | v_up (3) | L_up (3) | dh = (dx, dz, dtheta) (3)]",
            "g_lo": "[p_j (27) | v_j (27) | q6_j (54), j in lower_body_joints | c_L c_R (2) | z (12)]",
            "g_up": "[p_j (36) | v_j (36) | q6_j (72), j in upper_body_joints]",
            "n3p_signal": "inv(h^{t-1}) o^t (27) -> z~^t (12)",
            "n3p_lower": "[z~^t (12) | g_lo^{t-1} (122)] -> [g_lo^t (122) | z*^{t+1} (12)]",
            "n3p_upper": "[inv(h^t) o^t (27) | g_up^{t-1} (144)] -> [g_up^t (144) | o*^{t+1} (27)]",
            "heading": "h = (p_x, p_z, theta_y); R_y(theta) maps +Z to (sin theta, 0, cos theta)",
        },
        "initial_state": init,
        "hidden": hidden,
        "standing_hips_height": STANDARD["standing_hips_height"],
        "standing_head_height": STANDARD["standing_head_height"],
    }
    return add_provenance(m, trained_on_bandai, training)


def export_nets(nets, prefix, init, training=None, trained_on_bandai=True, dtype="float32"):
    hidden = {s.name: s.hidden for s in nets}
    m = meta(init, hidden, training, trained_on_bandai)
    paths = []
    for s in nets:
        path = prefix + SUFFIX[s.name]
        sd = {k: v.detach().clone() for k, v in s.net.state_dict().items()}
        norm = {NORM_NAMES[k]: v for k, v in s.normalization().items()}
        write_weights(path, sd, s.kind, s.net.inputs, s.net.outputs, meta=m, normalization=norm,
                      dtype=dtype)
        paths.append(path)
    return paths
