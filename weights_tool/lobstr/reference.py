"""The Python reference pipeline that the C++ avatar::LoBSTrPipeline must match (parity test):
synthetic trackers from a clip at the model rate, as float32 OpenXR poses (what C++ receives),
calibration scale, the 37 features, and the network outputs in streaming and window modes.
"""
import numpy as np
import torch

from .features import features
from .rotations import matrix_to_quat, quat_to_matrix
from .skeleton import Clip
from .standard import STANDARD

STANDARD_LEG = float(np.linalg.norm(STANDARD["offsets"][STANDARD["names"].index("LowerLeg_L")]) +
                     np.linalg.norm(STANDARD["offsets"][STANDARD["names"].index("Foot_L")]))


def clip_ticks(clip, fps=30.0, start=0, count=None):
    """Tracker poses at the model rate (every k-th frame; the clip rate must be a multiple of fps),
    rounded to float32 as a C++ caller would pass them: positions [T, 4, 3], quats [T, 4, 4] (x,y,z,w)."""
    k = int(round(clip.fps / fps))
    if abs(clip.fps / k - fps) > 1e-3 * fps:
        raise ValueError(f"clip rate {clip.fps} is not a multiple of {fps}")
    P, Q = clip.trackers()
    P = P.copy()
    P[..., 1] -= clip.floor()
    idx = np.arange(start, clip.frames, k)
    if count:
        idx = idx[:count]
    return P[idx].astype(np.float32), matrix_to_quat(Q[idx]).astype(np.float32), idx


def run(model, mean, std, pos32, quat32, scale, window=30):
    """Features X [T, 37] (float64) and outputs (streaming [T, 52], window [T, 52]) of the reference."""
    P = pos32.astype(np.float64)
    Q = quat_to_matrix(quat32.astype(np.float64))
    X = features(P, Q, scale)
    xs = torch.from_numpy(((X.astype(np.float32) - mean) / std).astype(np.float32))[None]
    model.eval()
    with torch.no_grad():
        ys, _ = model(xs)
        yw = np.stack([model(xs[:, max(0, i - window + 1):i + 1])[0][0, -1].numpy() for i in range(X.shape[0])])
    return X, ys[0].numpy(), yw


def clip_scale(clip):
    return STANDARD_LEG / clip.leg
