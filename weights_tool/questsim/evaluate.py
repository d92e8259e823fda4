"""Evaluate a QuestSim policy over a folder of BVH clips (the validation split), through the run-time
pipeline (avatar::QuestSimPipeline via the `sparsebody` Python module) on the device-realistic stream
a headset session of each clip would record (72 Hz, headset at the eyes, controllers at the grips).

  /usr/bin/python3 -m weights_tool.questsim.evaluate POLICY.json VALDIR [--motions REGEX] [--every N [--offset K]]
      [--json OUT.json] [--plots DIR]

Per clip and in the summary (frames weighted):
  mpjpe_cm          mean joint position error of the 21 avatar bodies against the clip's joints of
                    the same name at the user time the character tracks (latency removed)
  mpjpe_output_cm   the same against the user's pose at the newest input time (as a user sees it)
  falls_per_min     Fall events per minute of input (each resets the character under the headset),
                    from the pipeline's own counter (QuestSim.summary()); simulation failures apart.
                    (Before 2026-12-07 this counted the per-frame `event` array, which repeats a tick's
                    event on the input frames that run no tick: at 72 Hz input and 36 Hz ticks, every
                    fall twice.)
  skate_cm_s        horizontal speed of the lower foot (Foot_L/R origin) while it is within 5 cm of the
                    floor, averaged over frames
  penetration_cm    mean depth of the lowest body origin below the floor (0 when above)
  jitter_m_s3       mean |third difference| of body positions per control tick (m/s^3)
  residual_N        0: the QuestSim pipeline has no residual force
The avatar is sized to the user as the pipeline documents: h = standing headset height / 0.936, from
the median headset height of the first second.
"""
import argparse
import glob
import json
import os
import re

import numpy as np

DEFAULT_MOTIONS = r"raise-up|wave|bye|bow|guide|call|respond|walk"


def load_sb():
    from .. import pymod
    sb = pymod.load(required=True)
    return sb


def run_policy(sb, policy, inp):
    """The pipeline on one session (read_input's dict), the avatar sized to the user: returns the
    pipeline, its run() output, the height and the session's falls and simulation failures. `event`
    holds the last tick's event on every input frame, also on frames that run no tick, so events are
    counted by the pipeline's counters (summary()), not from that array."""
    t, P, Q, V = inp["time"], inp["position"], inp["orientation"], inp["valid"]
    first = t <= t[0] + 1.0
    h = float(np.median(P[first & V[:, 0], 0, 1])) / 0.936
    q = sb.QuestSim(policy, h)
    out = q.run(t, P, Q, V)
    summary = q.summary()
    return q, out, h, int(summary["falls"]), int(summary["simulation_failures"])


def evaluate_clip(sb, policy, path):
    inp = sb.read_input(path, devices=True)
    t = inp["time"]
    q, out, h, falls, failures = run_policy(sb, policy, inp)
    names = q.bodies
    jn = inp["truth_joints"]
    idx = [jn.index(n) for n in names]
    truth = inp["truth_position"][:, idx, :]
    ft = inp["clip_frame_time"]

    def truth_at(time):
        x = np.clip(time / ft, 0, truth.shape[0] - 1)
        f0 = np.floor(x).astype(int)
        f1 = np.minimum(f0 + 1, truth.shape[0] - 1)
        a = (x - f0)[:, None, None]
        return (1 - a) * truth[f0] + a * truth[f1]

    ticked = (out["ticks"] > 0) & np.isfinite(out["tracked_time"])
    # `event` holds the last tick's event on every input frame, also on frames that run no tick, so
    # events are counted by the pipeline's counters and placed in time on the frames that ticked.
    ev = out["event"]
    B = out["body_position"][ticked]
    tt = out["tracked_time"][ticked]
    tn = t[ticked]
    res = {"clip": os.path.basename(path), "height_m": h, "ticks": int(ticked.sum()), "input_s": float(t[-1] - t[0])}
    if len(B) < 4:
        res["error"] = "fewer than 4 control ticks"
        return res, None
    err = np.linalg.norm(B - truth_at(tt), axis=2).mean(1)
    err_out = np.linalg.norm(B - truth_at(tn), axis=2).mean(1)
    dt = np.diff(tn)
    fl, fr = names.index("Foot_L"), names.index("Foot_R")
    feet = B[:, [fl, fr], :]
    lower = np.argmin(feet[:, :, 1], axis=1)
    foot = feet[np.arange(len(B)), lower]
    v = np.linalg.norm(np.diff(foot[:, [0, 2]], axis=0), axis=1) / np.maximum(dt, 1e-6)
    near = foot[1:, 1] < foot[:, 1].min() + 0.05
    jerk = np.diff(B, n=3, axis=0)
    minutes = res["input_s"] / 60
    res.update({
        "mpjpe_cm": 100 * float(err.mean()), "mpjpe_output_cm": 100 * float(err_out.mean()),
        "falls": falls, "simulation_failures": failures,
        "falls_per_min": float(falls / max(minutes, 1e-9)),
        "skate_cm_s": 100 * float(v[near].mean()) if near.any() else 0.0,
        "penetration_cm": 100 * float(np.maximum(0, -B[:, :, 1].min(1)).mean()),
        "jitter_m_s3": float(np.linalg.norm(jerk, axis=2).mean() * 36.0 ** 3) if len(jerk) else 0.0,
        "residual_N": 0.0,
    })
    series = {"time": tn, "error": err, "foot_y": feet[:, :, 1], "events": ev[ticked]}
    return res, series


def summarize(rows):
    ok = [r for r in rows if "error" not in r]
    w = np.array([r["ticks"] for r in ok], float)
    s = {"clips": len(ok), "skipped": len(rows) - len(ok), "input_min": sum(r["input_s"] for r in ok) / 60}
    for k in ("mpjpe_cm", "mpjpe_output_cm", "skate_cm_s", "penetration_cm", "jitter_m_s3"):
        s[k] = float(np.average([r[k] for r in ok], weights=w)) if ok else float("nan")
    s["falls"] = sum(r["falls"] for r in ok)
    s["simulation_failures"] = sum(r["simulation_failures"] for r in ok)
    s["falls_per_min"] = s["falls"] / max(s["input_min"], 1e-9)
    s["residual_N"] = 0.0
    return s


def plot_clip(series, res, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    ax[0].plot(series["time"], 100 * series["error"])
    falls = series["time"][series["events"] == 5]
    for f in falls:
        ax[0].axvline(f, color="r", lw=0.8)
    ax[0].set_ylabel("MPJPE (cm)"); ax[0].set_title(f"{res['clip']}: QuestSim, red = fall")
    ax[1].plot(series["time"], series["foot_y"][:, 0], label="Foot_L")
    ax[1].plot(series["time"], series["foot_y"][:, 1], label="Foot_R")
    ax[1].set_ylabel("ankle height (m)"); ax[1].set_xlabel("input time (s)"); ax[1].legend()
    fig.tight_layout(); fig.savefig(png, dpi=80); plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="weights_tool.questsim.evaluate")
    ap.add_argument("policy")
    ap.add_argument("clips")
    ap.add_argument("--motions", default=DEFAULT_MOTIONS)
    ap.add_argument("--every", type=int, default=1, help="every Nth clip (sorted by name)")
    ap.add_argument("--offset", type=int, default=0, help="starting at clip K: --every 2 --offset 0/1 split the folder in two halves")
    ap.add_argument("--json")
    ap.add_argument("--plots")
    a = ap.parse_args(argv)
    sb = load_sb()
    rx = re.compile(a.motions)
    if a.every < 1 or not 0 <= a.offset < a.every:
        raise SystemExit(f"--every {a.every} --offset {a.offset}: expected every >= 1 and 0 <= offset < every")
    paths = [p for p in sorted(glob.glob(os.path.join(a.clips, "*.bvh"))) if rx.search(os.path.basename(p))][a.offset::a.every]
    if not paths:
        raise SystemExit(f"error: no clips in {a.clips} match {a.motions!r}")
    rows = []
    if a.plots:
        os.makedirs(a.plots, exist_ok=True)
    for p in paths:
        r, series = evaluate_clip(sb, a.policy, p)
        rows.append(r)
        if a.plots and series is not None:
            plot_clip(series, r, os.path.join(a.plots, r["clip"].replace(".bvh", ".png")))
    s = summarize(rows)
    print(json.dumps(s, indent=1))
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"summary": s, "clips": rows, "policy": a.policy}, f, indent=1)


if __name__ == "__main__":
    main()
