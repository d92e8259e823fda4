"""Golden files for the C++ pipeline parity test (tests/pipeline/): a small random LoBSTr network
(H=32, latent 16) with the pipeline metadata, and the reference pipeline's trackers, features and
outputs on a CMU clip from Debian's assimp-testmodels (never Bandai Namco data).
"""
import json
import os

import numpy as np
import torch

from ..format import write_weights
from ..nets import LoBSTrNet
from . import reference
from .export import pipeline_meta
from .skeleton import Clip

DEFAULT_CLIP = "/usr/share/assimp/models/BVH/01_01.bvh"


def write(out_dir, clip_path=DEFAULT_CLIP, start=0, count=150, seed=7):
    os.makedirs(out_dir, exist_ok=True)
    clip = Clip(clip_path)
    pos, quat, idx = reference.clip_ticks(clip, 30.0, start, count)
    scale = reference.clip_scale(clip)
    torch.manual_seed(seed)
    model = LoBSTrNet(hidden=32, latent=16)
    with torch.no_grad():  # larger weights than the default init, so the outputs move visibly
        for p in model.parameters():
            p.mul_(2.0)
    from .features import features
    from .rotations import quat_to_matrix
    X0 = features(pos.astype(np.float64), quat_to_matrix(quat.astype(np.float64)), scale)
    mean = X0.mean(0).astype(np.float32)
    std = np.maximum(X0.std(0), 1e-3).astype(np.float32)
    wpath = os.path.join(out_dir, "lobstr_pipeline_small.weights.json")
    write_weights(wpath, model.state_dict(), "lobstr", 37, 52,
                  meta=pipeline_meta(32, 16, trained_on_bandai=False),
                  normalization={"input_mean": mean, "input_std": std})
    X, ys, yw = reference.run(model, mean, std, pos, quat, scale, window=30)
    g = {
        "source": f"{os.path.basename(clip_path)} (CMU Graphics Lab Motion Capture Database via cgspeed "
                  f"BVH conversion, Debian assimp-testmodels), frames {int(idx[0])}..{int(idx[-1])} step "
                  f"{int(idx[1] - idx[0])}",
        "clip": os.path.basename(clip_path), "clip_frames": [int(i) for i in idx],
        "frame_rate": 30.0, "scale": scale, "window": 30,
        "positions": pos.astype(np.float64).tolist(), "quaternions_xyzw": quat.astype(np.float64).tolist(),
        "features": X.tolist(), "outputs": ys.astype(np.float64).tolist(), "window_outputs": yw.astype(np.float64).tolist(),
    }
    gpath = os.path.join(out_dir, "lobstr_pipeline_small.golden.json")
    with open(gpath, "w") as f:
        json.dump(g, f, separators=(",", ":"))
    return wpath, gpath
