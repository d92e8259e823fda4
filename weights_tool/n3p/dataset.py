"""BVH clips -> world-space arrays for Neural3Points training and evaluation (cached .npz).

Uses the LoBSTr engineer's BVH loader and tracker synthesis (weights_tool/lobstr/skeleton.py): the
tracker o_X is the head / hand joint position with the calibrated orientation (at the first frame
every tracker has the body's facing frame: X left, Y up, Z forward), the convention of
features/calibration.hpp. Heights are above the clip's floor. Per frame (metres, world, Y up):
  P [21, 3], Q6 [21, 6], V [21, 3]   standard-skeleton joint positions, 6D orientations, velocities
  TP [3, 3], TQ6 [3, 6]              trackers H, L, R
  H [3]                              ground-truth heading (hips x, hips z, theta_y of the pelvis forward)
  C, Cv, L [3]                       upper-body centroid, its velocity, angular momentum (unit masses)
  CT [2]                             foot contacts (LoBSTr labels: toe near the floor and slow)
"""
import glob
import os
import time

import numpy as np

from ..lobstr.rotations import to6d
from ..lobstr.skeleton import Clip, contact_labels
from .layout import FPS, I_UP, NAMES

KEYS = ("P", "Q6", "V", "TP", "TQ6", "H", "C", "Cv", "L", "CT")


def velocity(x, fps):
    v = np.zeros_like(x)
    if len(x) > 1:
        v[1:] = (x[1:] - x[:-1]) * fps
        v[0] = v[1]
    return v


def tracker_arrays(clip):
    """Tracker world positions [F, 3, 3] (floor at y = 0), 6D orientations [F, 3, 6], heading [F, 3]."""
    floor = clip.floor()
    TP, TQ = clip.trackers()
    TP = TP.copy()
    TP[..., 1] -= floor
    fwd = TQ[:, 3, :, 2]
    theta = np.unwrap(np.arctan2(fwd[:, 0], fwd[:, 2]))
    hips = TP[:, 3]
    H = np.stack([hips[:, 0], hips[:, 2], theta], -1)
    return TP[:, :3], to6d(TQ[:, :3]), H, floor


def clip_arrays(clip):
    b = clip.bvh
    idx = [b.index(n) for n in NAMES]
    TP, TQ6, H, floor = tracker_arrays(clip)
    P = clip.pw[:, idx].copy()
    P[..., 1] -= floor
    Q6 = to6d(clip.Rw[:, idx])
    V = velocity(P, clip.fps)
    Pu, Vu = P[:, I_UP], V[:, I_UP]
    C = Pu.mean(1)
    Cv = Vu.mean(1)
    L = np.cross(Pu - C[:, None], Vu - Cv[:, None]).mean(1)
    CT = contact_labels(clip, floor).astype(np.float32)
    return dict(P=P, Q6=Q6, V=V, TP=TP, TQ6=TQ6, H=H, C=C, Cv=Cv, L=L, CT=CT)


def clip_arrays_devices(clip, rng):
    """clip_arrays of the clip at a random speed, with the tracker inputs taken from a random body with
    device-realistic trackers (weights_tool/devices.py) scaled by the height scale the runtime finds.
    Targets stay the standard skeleton's (the predictor's output skeleton). The varied body's normalised
    ground track is moved onto the standard one's so the inputs and the heading targets agree."""
    from .. import devices
    aug = devices.Augment(rng)
    cs = devices.retime(clip, aug.speed)
    cv = devices.scale_body(cs, aug)
    a = clip_arrays(cs)
    P, Q, s = devices.device_trackers(cv, aug)
    TP = P[:, :3] * s
    hips = clip.roles["hips"]
    shift = cs.pw[:, hips, [0, 2]] - s * cv.pw[:, hips, [0, 2]]
    TP[..., 0] += shift[:, None, 0]
    TP[..., 2] += shift[:, None, 1]
    a["TP"], a["TQ6"] = TP, to6d(Q[:, :3])
    return a


def build(data_dir, out_path, every=1, limit=None, device_realisations=0, plain=True, seed=0):
    """plain: the clip with trackers at the joints (as before); device_realisations: that many more
    copies per clip from clip_arrays_devices (seeded)."""
    rng = np.random.default_rng(seed)
    files = sorted(glob.glob(os.path.join(data_dir, "*.bvh")))[::every]
    if limit:
        files = files[:limit]
    parts = {k: [] for k in KEYS}
    lens, names = [], []
    t = time.time()
    for n, f in enumerate(files):
        clip = Clip(f)
        if clip.frames < 8 or abs(clip.fps - FPS) > 0.5:
            continue
        arrays = ([clip_arrays(clip)] if plain else []) + [clip_arrays_devices(clip, rng) for _ in range(device_realisations)]
        for a in arrays:
            for k in KEYS:
                parts[k].append(a[k].astype(np.float32))
            lens.append(len(a["P"]))
            names.append(os.path.basename(f))
        if n % 100 == 0:
            print(f"  {n}/{len(files)} clips, {time.time() - t:.0f} s", flush=True)
    np.savez(out_path, lens=np.array(lens), names=np.array(names), **{k: np.concatenate(v) for k, v in parts.items()})
    print(f"wrote {out_path}: {len(lens)} clips, {sum(lens)} frames", flush=True)


class Data:
    def __init__(self, path):
        d = np.load(path)
        self.a = {k: d[k] for k in KEYS}
        self.lens = d["lens"]
        self.names = d["names"]
        self.starts = np.concatenate([[0], np.cumsum(self.lens)[:-1]]).astype(np.int64)

    def clip(self, i):
        s, n = self.starts[i], self.lens[i]
        return {k: v[s:s + n] for k, v in self.a.items()}
