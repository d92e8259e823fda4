"""Evaluation on a BVH folder (the validation split): the paper's Table 1 metrics and more.

Trackers are synthesised with the paper's noise (fixed seed); the network runs over each whole clip
in streaming mode and, with --window, in window mode (each frame from the last 30 frames, zero
state). The predicted lower body is placed under the ground-truth hips (as in the paper's offline
evaluation; no contact IK - the C++ demo reports the post-processed pipeline).
  contact accuracy   predicted class (argmax per foot) vs labels (skeleton.contact_labels)
  rotational error   mean geodesic angle over the 8 lower-body local rotations (degrees)
  positional error   mean toe-base position error (cm)
  MPJPE lower body   mean over the 8 lower-body joints (cm)
  jitter             mean |third difference| of lower-body joint positions x fps^3 (km/s^3)
  foot skating       mean horizontal toe speed while the predicted contact is on (cm/s)
"""
import argparse
import glob
import os

import numpy as np
import torch

from ..nets import LoBSTrNet
from . import bvh
from .dataset import clip_arrays
from .rotations import angle_between, from6d
from .skeleton import LOWER, Clip, contact_labels


def load_model(path):
    if path.endswith(".json"):  # an exported weights file
        from ..format import read_weights
        doc, tensors, norm = read_weights(path)
        cfg = {"hidden": doc["meta"]["hidden"], "latent": doc["meta"]["latent"]}
        m = LoBSTrNet(hidden=cfg["hidden"], latent=cfg["latent"])
        m.load_state_dict({k: torch.from_numpy(v).float() for k, v in tensors.items()})
        m.eval()
        return m, norm["input_mean"].astype(np.float32), norm["input_std"].astype(np.float32), cfg
    ck = torch.load(path, map_location="cpu")
    cfg = ck["config"]
    m = LoBSTrNet(hidden=cfg["hidden"], latent=cfg["latent"])
    m.load_state_dict(ck["state_dict"])
    m.eval()
    n = ck["normalization"]
    return m, n["input_mean"].numpy(), n["input_std"].numpy(), cfg


def predict(model, mean, std, X, window=None):
    x = torch.from_numpy(((X - mean) / std).astype(np.float32))
    with torch.no_grad():
        if not window:
            return model(x[None])[0][0].numpy()
        T = x.shape[0]
        out = np.empty((T, 52), np.float32)
        for i in range(T):  # window [i - window + 1, i] from a zero state, shorter at the start
            lo = max(0, i - window + 1)
            out[i] = model(x[None, lo:i + 1])[0][0, -1].numpy()
        return out


def clip_metrics(clip, Yp, C):
    F = clip.frames
    lower = [clip.bvh.index(n) for n in LOWER]
    R_pred = from6d(Yp[:, :48].reshape(F, 8, 6))
    rot = angle_between(R_pred, clip.R_local[:, lower]).mean()
    Rl = clip.R_local.copy()
    Rl[:, lower] = R_pred
    _, pw = bvh.fk(clip.bvh.parents, Rl, clip.t_local)
    toes = [clip.roles["toe_l"], clip.roles["toe_r"]]
    toe_err = np.linalg.norm(pw[:, toes] - clip.pw[:, toes], axis=-1).mean()
    mpjpe = np.linalg.norm(pw[:, lower] - clip.pw[:, lower], axis=-1).mean()
    pc = Yp[:, 48:].reshape(F, 2, 2).argmax(-1)
    acc = (pc == C).mean()
    fps = clip.fps
    jit = np.linalg.norm(np.diff(pw[:, lower], n=3, axis=0), axis=-1).mean() * fps ** 3 if F > 3 else np.nan
    jit_gt = np.linalg.norm(np.diff(clip.pw[:, lower], n=3, axis=0), axis=-1).mean() * fps ** 3 if F > 3 else np.nan
    v = np.linalg.norm(np.diff(pw[:, toes][..., [0, 2]], axis=0), axis=-1) * fps  # [F-1, 2]
    on = pc[1:] == 1
    skate = (v * on).sum() / max(on.sum(), 1)
    vg = np.linalg.norm(np.diff(clip.pw[:, toes][..., [0, 2]], axis=0), axis=-1) * fps
    skate_gt = (vg * (C[1:] == 1)).sum() / max((C[1:] == 1).sum(), 1)
    return dict(frames=F, contact=acc, rot=rot, toe=toe_err, mpjpe=mpjpe, jitter=jit, jitter_gt=jit_gt,
                skate=skate, skate_gt=skate_gt, n_on=on.sum(), n_on_gt=(C[1:] == 1).sum())


def evaluate(model_path, data_dir, window=None, limit=None, seed=1, every=1, devices=False):
    model, mean, std, cfg = load_model(model_path)
    rng = np.random.default_rng(seed)
    files = sorted(glob.glob(os.path.join(data_dir, "*.bvh")))[::every]
    if limit:
        files = files[:limit]
    rows = []
    for f in files:
        clip = Clip(f)
        if clip.frames < 8:
            continue
        if devices:  # a random body with device-realistic trackers (weights_tool/devices.py)
            from .dataset import clip_arrays_devices
            X, _, C, clip = clip_arrays_devices(clip, rng, return_clip=True)
        else:
            X, _, C = clip_arrays(clip, rng)
        Yp = predict(model, mean, std, X, window)
        rows.append(clip_metrics(clip, Yp, C))
    w = np.array([r["frames"] for r in rows], float)
    avg = {k: float(np.nansum([r[k] * r["frames"] for r in rows]) / w.sum())
           for k in ("contact", "rot", "toe", "mpjpe", "jitter", "jitter_gt")}
    for k, n in (("skate", "n_on"), ("skate_gt", "n_on_gt")):
        avg[k] = float(sum(r[k] * r[n] for r in rows) / max(1, sum(r[n] for r in rows)))
    avg["clips"], avg["frames"] = len(rows), int(w.sum())
    return avg, cfg


def main(argv=None):
    p = argparse.ArgumentParser(prog="weights_tool.lobstr evaluate")
    p.add_argument("checkpoint")
    p.add_argument("data_dir", help="BVH folder, e.g. the unpacked validation split")
    p.add_argument("--window", type=int, default=0, help="window mode with this many frames (0: streaming)")
    p.add_argument("--limit", type=int)
    p.add_argument("--every", type=int, default=1, help="use every n-th clip")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--devices", action="store_true", help="random bodies and device-realistic trackers")
    a = p.parse_args(argv)
    torch.set_num_threads(a.threads)
    avg, cfg = evaluate(a.checkpoint, a.data_dir, a.window or None, a.limit, every=a.every, devices=a.devices)
    mode = (f"window ({a.window} frames)" if a.window else "streaming") + (", device-realistic" if a.devices else "")
    print(f"LoBSTr H={cfg['hidden']} latent={cfg['latent']}, {mode}, {avg['clips']} clips, {avg['frames']} frames "
          f"of {a.data_dir}")
    print(f"  contact accuracy     {100 * avg['contact']:6.2f} %     (paper GRU: 85.77 %)")
    print(f"  rotational error     {avg['rot']:6.2f} deg   (paper GRU: 8.53 deg)")
    print(f"  toe positional error {100 * avg['toe']:6.2f} cm    (paper GRU: 6.63 cm)")
    print(f"  MPJPE lower body     {100 * avg['mpjpe']:6.2f} cm")
    print(f"  jitter lower body    {avg['jitter'] / 1000:6.2f} km/s^3 (ground truth {avg['jitter_gt'] / 1000:.2f})")
    print(f"  foot skating         {100 * avg['skate']:6.2f} cm/s  (ground truth {100 * avg['skate_gt']:.2f})")
    return 0
