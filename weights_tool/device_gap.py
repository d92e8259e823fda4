"""Where the device session's error comes from (issue 12): offdist's `devices` mode against its
`nominal` mode, one difference at a time, on the same clips, per joint, and per clip.

Steps, each adding one difference to the one before (MPJPE over the clip's own frames, the 2.5 s
stand excluded; offdist's 12 joints by role, floor y = 0):
  nominal        trackers at the joints, sized by the clip's leg length (offdist `nominal`)
  +stand         the clip's first frame held for 2.5 s first (as `devices` does)
  +eye sizing    sized from the standing head height instead (what calibration can see)
  +devices       the device stream: headset at the eyes, grips off the wrists, 72 Hz, OpenXR
                 conventions, the device model's offsets exactly; automatic calibration on the stand
  +per user      per-session perturbation of the offsets and mountings, 2 ms jitter, losses (offdist
                 `devices`, the same seeds)
Per clip it also gives the calibrated scale over the leg-based one: above 1.03 the held first frame
is a bent stance (a run's start, a crouched "active" style), which calibration takes for a stand.

  /usr/bin/python3 -m weights_tool.device_gap VALIDATION_DIR [--every 5] [--models lobstr n3p] [--json F]
"""
import argparse
import glob
import json
import os
import sys

import numpy as np

from . import offdist, pymod
from .lobstr.skeleton import Clip

STAND = 2.5  # s, as offdist's devices mode (--devices-stand 0)
STEPS = ["nominal", "+stand", "+eye sizing", "+devices", "+per user"]
BENT = 1.03


def standing_head_height(model):
    path = pymod.load(required=True).default_weights(model)
    if not os.path.isfile(path):  # Neural3Points: a prefix of its three files
        path += "_lower.json"
    with open(path) as f:
        return float(json.load(f)["meta"]["standing_head_height"])


def errors(P, truth, skip):
    """Per-frame, per-role position errors [n, 12] (m) of output rows P [n, 12, 3] against the clip,
    row i showing clip frame i - skip."""
    i = np.arange(len(P))
    ti = i - skip
    keep = (ti >= 0) & (ti < truth.frames)
    Pt = truth.pw[ti[keep]][:, [truth.roles[k] for k in offdist.ROLES]].copy()
    Pt[..., 1] -= truth.floor()
    return np.linalg.norm(P[keep] - Pt, axis=-1)


def held(inp, n):
    """read_input's dict with its first frame held for n frames first (same frame time)."""
    out = dict(inp)
    dt = inp["time"][1] - inp["time"][0]
    for k in ("position", "orientation", "valid"):
        out[k] = np.concatenate([np.repeat(inp[k][:1], n, 0), inp[k]])
    out["time"] = inp["time"][0] + np.arange(len(out["position"])) * dt
    return out


def joints_run(sb, model, inp, scale=None):
    pipe = sb.create(model)
    s_leg = pipe.fit_leg_length(inp["leg"])
    if scale is not None:
        pipe.set_scale(scale)
    r = pymod.Run(pipe, inp, pipe.run(inp["time"], inp["position"], inp["orientation"], inp["valid"]))
    return r.bvh_positions()[:, [pipe.roles[k] for k in offdist.ROLES]], s_leg


def clip_gap(sb, model, path, seed, head_std):
    truth = Clip(path)
    inp = sb.read_input(path)
    dt = inp["time"][1] - inp["time"][0]
    if abs(dt - 1 / 30) > 1e-6:  # output rows are 30 Hz model frames, one per clip frame
        raise ValueError(f"{path}: frame time {dt:.6f} s; device_gap takes 30 fps clips (the validation split)")
    nh = int(round(STAND / dt))
    e = {}
    P, s_leg = joints_run(sb, model, inp)
    e["nominal"] = errors(P, truth, 0)
    stand = held(inp, nh)
    e["+stand"] = errors(joints_run(sb, model, stand)[0], truth, nh)
    e["+eye sizing"] = errors(joints_run(sb, model, stand, head_std / inp["position"][0, 0, 1])[0], truth, nh)
    rows = int(round(STAND * 30))  # the pipelines' output rows are 30 Hz model frames
    for step, s in (("+devices", 0), ("+per user", seed)):
        r = pymod.run_clip(sb, path, model=model, devices=True, devices_stand=0.0, device_seed=s)
        e[step] = errors(r.bvh_positions()[:, [r.pipe.roles[k] for k in offdist.ROLES]], truth, rows)
        if step == "+devices":
            scale = r.pipe.calibration_report()["scale"]
    return e, scale / s_leg


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("validation")
    ap.add_argument("--every", type=int, default=5)
    ap.add_argument("--models", nargs="+", default=["lobstr", "n3p"])
    ap.add_argument("--json", default="")
    a = ap.parse_args(argv)
    sb = pymod.load(required=True)
    files = sorted(glob.glob(os.path.join(a.validation, "*.bvh")))[::a.every]
    if not files:
        sys.exit(f"{a.validation}: no .bvh files")
    report = {}
    for model in a.models:
        head_std = standing_head_height(model)
        per = []
        for ci, path in enumerate(files):
            e, ratio = clip_gap(sb, model, path, 1000 + ci, head_std)  # offdist's seeds
            per.append((os.path.basename(path), ratio, e))
        print(f"\n{model}: {len(files)} clips (every {a.every}th), MPJPE cm after the stand; per joint: " + " ".join(offdist.ROLES))
        out = {"steps": {}, "bent_stand": {}, "clips": []}
        for step in STEPS:
            E = np.concatenate([p[2][step] for p in per])
            print(f"  {step:12s} {100 * E.mean():5.2f}   " + " ".join(f"{100 * x:5.2f}" for x in E.mean(0)))
            out["steps"][step] = {"mpjpe_cm": 100 * E.mean(), "per_joint_cm": dict(zip(offdist.ROLES, (100 * E.mean(0)).tolist()))}
        for name, sel in (("stand upright", lambda p: p[1] <= BENT), ("bent stand", lambda p: p[1] > BENT)):
            sub = [p for p in per if sel(p)]
            if not sub:
                continue
            line = {step: 100 * np.concatenate([p[2][step] for p in sub]).mean() for step in STEPS}
            print(f"  {name} ({len(sub)} clips, calibrated / leg scale {'<=' if name.startswith('stand') else '>'} {BENT}): " +
                  ", ".join(f"{k} {v:.2f}" for k, v in line.items()))
            out["bent_stand"][name] = {"clips": len(sub), **line}
        out["clips"] = [{"clip": n, "scale_ratio": r, **{k: 100 * v.mean() for k, v in e.items()}} for n, r, e in per]
        report[model] = out
    if a.json:
        with open(a.json, "w") as f:
            json.dump(report, f, indent=1)


if __name__ == "__main__":
    main()
