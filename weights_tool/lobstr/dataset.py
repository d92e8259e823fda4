"""Clips -> cached arrays for training and evaluation.

Per clip: features X [F, 37] from synthetic noisy trackers (several noise realisations for the
training split), targets Y [F, 48] (8 lower-body local rotations, 6D), contacts C [F, 2], and the
ground truth needed by the metrics. Cached as one .npz per split under the cache directory.
"""
import glob
import os
import time

import numpy as np

from . import features as feat
from .rotations import random_rotations, to6d
from .skeleton import LOWER, Clip, add_tracker_noise, contact_labels


def clip_arrays(clip, rng=None, offset_deg=0.0, scale_jitter=0.0):
    """Features, targets and contacts of one clip in the standard skeleton (the Bandai one).
    With rng: paper noise, plus per-clip tracker rotational offsets (calibration error) up to
    offset_deg and a height-scale error up to +-scale_jitter."""
    floor = clip.floor()
    P, Q = clip.trackers()
    P = P.copy()
    P[..., 1] -= floor
    s = 1.0
    if rng is not None:
        P, Q = add_tracker_noise(rng, P, Q)
        if offset_deg > 0:
            Q[:, :3] = Q[:, :3] @ random_rotations(rng, 3, offset_deg)[None]
        s = 1.0 + rng.uniform(-scale_jitter, scale_jitter)
    X = feat.features(P, Q, s)
    idx = [clip.bvh.index(n) for n in LOWER]
    Y = to6d(clip.R_local[:, idx]).reshape(clip.frames, 48)
    C = contact_labels(clip, floor)
    return X.astype(np.float32), Y.astype(np.float32), C


def clip_arrays_devices(clip, rng, return_clip=False):
    """Features, targets and contacts of one clip on a random body at a random speed, with trackers
    placed like real devices (weights_tool/devices.py)."""
    from .. import devices
    aug = devices.Augment(rng)
    c = devices.scale_body(devices.retime(clip, aug.speed), aug)
    P, Q, s = devices.device_trackers(c, aug)
    X = feat.features(P, Q, s)
    idx = [c.bvh.index(n) for n in LOWER]
    Y = to6d(c.R_local[:, idx]).reshape(c.frames, 48)
    C = contact_labels(c, c.floor())
    if return_clip:
        return X.astype(np.float32), Y.astype(np.float32), C, c
    return X.astype(np.float32), Y.astype(np.float32), C


def build(data_dir, out_path, realisations=1, seed=0, limit=None, offset_deg=0.0, scale_jitter=0.0, every=1,
          device_realisations=0):
    """realisations: noisy trackers at the joints (the paper's setting); device_realisations: more
    realisations per clip from clip_arrays_devices."""
    files = sorted(glob.glob(os.path.join(data_dir, "*.bvh")))[::every]
    if limit:
        files = files[:limit]
    rng = np.random.default_rng(seed)
    Xs, Ys, Cs, lens, names = [], [], [], [], []
    t = time.time()
    for n, f in enumerate(files):
        clip = Clip(f)
        if clip.frames < 8:
            continue
        for r in range(realisations):
            X, Y, C = clip_arrays(clip, rng if realisations > 0 else None, offset_deg, scale_jitter)
            Xs.append(X), Ys.append(Y), Cs.append(C), lens.append(len(X)), names.append(os.path.basename(f))
        for r in range(device_realisations):
            X, Y, C = clip_arrays_devices(clip, rng)
            Xs.append(X), Ys.append(Y), Cs.append(C), lens.append(len(X)), names.append(os.path.basename(f))
        if n % 200 == 0:
            print(f"  {n}/{len(files)} clips, {time.time() - t:.0f} s", flush=True)
    np.savez(out_path, X=np.concatenate(Xs), Y=np.concatenate(Ys), C=np.concatenate(Cs),
             lens=np.array(lens), names=np.array(names))
    print(f"wrote {out_path}: {len(lens)} sequences, {sum(lens)} frames")


def load(path):
    d = np.load(path)
    lens = d["lens"]
    starts = np.concatenate([[0], np.cumsum(lens)[:-1]])
    return d["X"], d["Y"], d["C"], lens, starts, d["names"]
