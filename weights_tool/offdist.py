"""Off-distribution measures of the whole C++ pipeline (issue 12, item 5), from the demo's output BVH
against the clip that drove it, the same way for every input path:

  nominal  validation BVH, trackers synthesised at the joints (the in-distribution setting)
  devices  validation BVH, device-realistic trackers (eye point, grips, per-clip random user offsets,
           jitter, losses, 72 Hz: the demo's --devices --device-seed) and automatic calibration, as a
           session that starts with the user standing for 2.5 s (--devices-stand 0: the clip's first
           frame held; the held frames are compared with that frame)
  s155, s190, longlegs, shortlegs   the same on validation clips retargeted to other bodies
           (weights_tool/bodies.py presets; also s172, longarms, shortarms: 1.72 m with standard,
           x1.08 and x0.92 arms)
  csv      the device-realistic stream written as the demo's tracker CSV (--trackers-out) and read
           back through the CSV path with default options: no T-pose, the user moving from the first
           frame (the default body until then) and standing 2.5 s half-way through the clip
  csvstop  the same, but the stand holds the frame nearest half-way where both feet are on the floor
           (a real user stops on both feet; csv freezes whatever frame is half-way, often mid-stride,
           and the truth then stands with a foot in the air)
  swapped  devices with the controllers in the other hands (symmetric controllers whose roles the
           runtime gave the wrong way round), through the CSV path: the session written as the
           demo's tracker CSV with its left / right hand columns exchanged, read back
  noisy    devices with tracking noise, through the CSV path: white noise on every sample of the
           72 Hz stream, positions sigma 0.3 mm (headset) / 1 mm (controllers, belt), orientations
           0.2 deg per axis (add_tracking_noise; sub-millimetre static jitter is what headsets and
           controllers show, and a network fed velocities sees it amplified by the frame rate)
  table    devices through the CSV path, the session starting before the user picks the controllers
           up: 3 s standing (the first frame held) with both controllers lying flat on a table 0.45 m
           ahead at 0.76 m, a 0.5 s pick-up, then the devices session (controllers_on_a_table)
  seated   devices through the CSV path, the session starting seated: 5 s with the headset 0.42 m lower
           and 0.1 m ahead (4 mm of sway), the belt 0.47 m lower, the controllers on the lap (0.3 m
           ahead, 0.62 m high), a 1.5 s stand-up, then the devices session (seated_start)
  lookdown devices through the CSV path, the user looking down 25 deg (at the controllers) through
           the session's first stand: the headset pitched about the head joint for 2 s, a 0.5 s look
           up, then the session (look_down_at_start)
  cmu      the CMU clips of Debian's assimp-testmodels (another performer, another skeleton)

Metrics (12 joints mapped by role: hips, head, hands, thighs, knees, ankles, toes; metres -> cm):
  mpjpe        mean joint position error, world, floor at y = 0
  moving       mpjpe without the held stand's frames (devices, csv ...: the frames compared one to one
               with the clip's own motion, which the nominal run also covers; = mpjpe without a stand)
  lower        the same over hips and legs
  toe          toe-base position error
  skate        mean horizontal toe speed of the output while the clip's foot is in contact (cm/s)
  still_feet   mean horizontal toe speed of the output while the clip's performer stands still (head
               and both toes slower than 5 cm/s for >= 0.5 s) (cm/s)
  head         mean distance of the output's head joint from the clip's (the head joint sits where the
               eye-point offset puts it relative to the headset) (cm)
  jitter       mean jerk of the output's hips and leg joints, |third difference| x fps^3 (km/s^3, as
               the demo's "jitter (lower body)"; the clips' own is ~0.1-0.3)

  /usr/bin/python3 -m weights_tool.offdist [DEMO] VALIDATION_DIR --modes nominal devices s155 ... \\
        [--models lobstr n3p] [--every 5] [--json out.json] [--runner auto|module|demo] [--plots DIR]
        [-- extra demo options]

Runner: the sparsebody Python module (weights_tool/pymod.py) when it is importable, in-process and
with the demo's inputs, sizing and rows; else (or --runner demo) the demo as a subprocess, its output
BVH read back. The figures agree to the BVH's print rounding (README, "Use it from Python").
"""
import argparse
import copy
import glob
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

from . import pymod
from .lobstr.skeleton import Clip, contact_labels

ROLES = ["hips", "head", "hand_l", "hand_r", "upleg_l", "upleg_r", "leg_l", "leg_r", "foot_l", "foot_r",
         "toe_l", "toe_r"]
LOWER = ["hips", "upleg_l", "upleg_r", "leg_l", "leg_r", "foot_l", "foot_r", "toe_l", "toe_r"]
CMU = ["/usr/share/assimp/models/BVH/01_01.bvh", "/usr/share/assimp/models/BVH/01_03.bvh",
       "/usr/share/assimp/models/BVH/Boxing_Toes.bvh"]


def hspeed(p, fps):
    v = np.zeros(len(p))
    if len(p) > 1:
        v[1:] = np.linalg.norm(np.diff(p[:, [0, 2]], axis=0), axis=-1) * fps
        v[0] = v[1]
    return v


def still_mask(truth, P, fps, speed=0.05, seconds=0.5):
    """Frames in runs of >= `seconds` where the head and both toes move slower than `speed`."""
    r = truth.roles
    slow = (hspeed(P[:, ROLES.index("head")], fps) < speed) & (hspeed(P[:, ROLES.index("toe_l")], fps) < speed) & \
           (hspeed(P[:, ROLES.index("toe_r")], fps) < speed)
    out = np.zeros_like(slow)
    n = int(seconds * fps)
    i = 0
    while i < len(slow):
        if slow[i]:
            j = i
            while j < len(slow) and slow[j]:
                j += 1
            if j - i >= n:
                out[i:j] = True
            i = j
        else:
            i += 1
    return out


def compare(out_bvh, truth_bvh, truth_units=None, out_units=0.01, hold=None):
    """Per-frame sums of the metrics of one run (dict of (sum, count)). The demo writes centimetres;
    the clip's units are guessed from its leg length unless given. hold = (at, seconds): the run held
    the clip's frame at `at` s for `seconds` (the demo's --devices-stand): the output's held frames
    are compared with that frame, the rest with the clip one to one."""
    out = Clip(out_bvh, units=out_units)
    return compare_positions(out.pw[:, [out.roles[k] for k in ROLES]], truth_bvh, truth_units, hold)


def compare_positions(P_out, truth_bvh, truth_units=None, hold=None):
    """compare() of output positions P_out [frames, 12 ROLES, 3] (m, one row per 30 Hz output frame):
    the demo's BVH read back, or the Python module's rows (pymod.Run.bvh_positions)."""
    truth = Clip(truth_bvh, units=truth_units)
    out = _Positions(P_out)
    fps = truth.fps
    held = np.zeros(out.frames, dtype=bool)
    if hold is not None and abs(truth.fps - 30.0) < 0.5:
        f0, nh = int(round(hold[0] * fps)), int(round(hold[1] * fps))
        i = np.arange(out.frames)
        ti = np.where(i < f0, i, np.where(i < f0 + nh, f0, i - nh))
        keep = ti < truth.frames
        held = ((i >= f0) & (i < f0 + nh))[keep]
        sub = copy.copy(truth)
        sub.pw, sub.Rw = truth.pw[ti[keep]], truth.Rw[ti[keep]]
        truth, n = sub, int(keep.sum())
        out = copy.copy(out)
        out.pw = out.pw[:n]
    n = min(out.frames, truth.frames)
    if n < 2:
        return None
    Po = out.pw[:n]
    Pt = truth.pw[:n, [truth.roles[k] for k in ROLES]].copy()
    Pt[..., 1] -= truth.floor()
    if abs(truth.fps - 30.0) > 0.5:
        # the pipelines run at 30 Hz: compare output frame i with the clip at time i / 30
        t = np.arange(out.frames) / 30.0
        idx = np.minimum(np.round(t * truth.fps).astype(int), truth.frames - 1)
        Pt_full = truth.pw[:, [truth.roles[k] for k in ROLES]].copy()
        Pt_full[..., 1] -= truth.floor()
        Pt, Po, fps, n = Pt_full[idx], out.pw, 30.0, out.frames
        C = contact_labels(truth, truth.floor())[idx]
    else:
        C = contact_labels(truth, truth.floor())[:n]
    e = np.linalg.norm(Po - Pt, axis=-1)
    li = [ROLES.index(k) for k in LOWER]
    ti = [ROLES.index("toe_l"), ROLES.index("toe_r")]
    m = {"mpjpe": (e.sum(), e.size), "lower": (e[:, li].sum(), e[:, li].size), "toe": (e[:, ti].sum(), e[:, ti].size),
         "head": (e[:, ROLES.index("head")].sum(), n)}
    mov = ~held[:n]  # held has a row per output row kept (>= n)
    m["moving"] = (e[mov].sum(), e[mov].size)
    sk, skn = 0.0, 0
    for s, j in enumerate(ti):
        v = hspeed(Po[:, j], fps)
        sk += v[C[:, s] > 0].sum()
        skn += int((C[:, s] > 0).sum())
    m["skate"] = (sk, skn)
    st = still_mask(truth, Pt, fps)
    v = hspeed(Po[:, ti[0]], fps) + hspeed(Po[:, ti[1]], fps)
    m["still_feet"] = (v[st].sum() / 2, int(st.sum()))
    if len(Po) > 3:
        jerk = np.linalg.norm(np.diff(Po[:, li], n=3, axis=0), axis=-1) * fps ** 3 / 1000.0
        m["jitter"] = (jerk.sum(), jerk.size)
    m["frames"] = (n, 1)
    return m


class _Positions:
    """The part of a Clip that compare_positions reads: pw [frames, 12 ROLES, 3]."""

    def __init__(self, P):
        self.pw = np.asarray(P)

    @property
    def frames(self):
        return self.pw.shape[0]


def run_demo(demo, src, out, model, extra, trackers_out=None):
    cmd = [demo, src, "-o", out, "--quiet", "--model", model] + extra
    if trackers_out:
        cmd += ["--trackers-out", trackers_out]
    r = subprocess.run(cmd, capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


DEVICES = ["--devices", "--devices-stand", "0"]  # a session that starts with the user standing 2.5 s
CSV_MODES = ("csv", "csvstop", "swapped", "noisy", "table", "seated", "lookdown")
TABLE_SECONDS, PICKUP_SECONDS = 3.0, 0.5  # table mode: controllers on the table, then picked up
SEATED_SECONDS, STANDUP_SECONDS = 5.0, 1.5  # seated mode: seated, then standing up
LOOKDOWN_DEGREES, LOOKDOWN_SECONDS, LOOKUP_SECONDS = 25.0, 2.0, 0.5  # lookdown mode
EYE_OPENXR = np.array([0.0, 0.08, -0.10])  # the device model's eye point e in the headset's OpenXR frame (-Z ahead)
NOISE_POSITION = (0.0003, 0.001, 0.001, 0.001)  # m, sigma per axis: headset, left, right, belt
NOISE_ORIENTATION = np.radians(0.2)              # rad, sigma per axis


def _qmul(a, b):
    """Quaternion products a b of [..., 4] arrays, x y z w."""
    x1, y1, z1, w1 = np.moveaxis(a, -1, 0)
    x2, y2, z2, w2 = np.moveaxis(b, -1, 0)
    return np.stack([w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2, w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2], axis=-1)


class _TrackerCsv:
    """A tracker CSV as read back: its comment and header lines, column names, rows [n, columns]."""

    def __init__(self, path):
        with open(path) as f:
            lines = f.readlines()
        h = next(k for k, l in enumerate(lines) if not l.startswith("#"))
        self.head, self.cols = lines[:h + 1], lines[h].strip().split(",")
        self.rows = np.array([[float(x) for x in l.strip().split(",")] for l in lines[h + 1:] if l.strip()])
        self.c = {n: i for i, n in enumerate(self.cols)}

    def index(self, name, what):
        """Column indices of a tracker's position ("p": x y z) or orientation ("q": x y z w)."""
        return [self.c[f"{name}_{what}{a}"] for a in ("xyz" if what == "p" else "xyzw")]

    def forward(self, row):
        """The headset's -Z in a row, horizontal, unit length (where the user looks)."""
        x, y, z, w = row[self.index("head", "q")]
        f = -np.array([2 * (x * z + w * y), 0.0, 1 - 2 * (x * x + y * y)])
        return f / np.linalg.norm(f)

    def prepend(self, pre, rate):
        """Rows `pre` put before the session at `rate` Hz, the session's own time-shifted, time 0 first."""
        pre[:, 0] = self.rows[0, 0] + (np.arange(len(pre)) - len(pre)) / rate
        self.rows = np.vstack([pre, self.rows])
        self.rows[:, 0] -= self.rows[0, 0]

    def write(self, path):
        valid = [i for i, n in enumerate(self.cols) if n.endswith("_valid")]
        with open(path, "w") as f:
            f.writelines(self.head)
            for r in self.rows:
                f.write(",".join(str(int(v)) if i in valid else f"{v:.9g}" for i, v in enumerate(r)) + "\n")


def add_tracking_noise(path, seed):
    """Adds white tracking noise (NOISE_POSITION, NOISE_ORIENTATION) to every sample of a tracker CSV:
    each position moved by a Gaussian offset, each orientation turned by a small Gaussian rotation."""
    csv = _TrackerCsv(path)
    rows = csv.rows
    rng = np.random.default_rng(seed)
    for k, name in enumerate(("head", "left_hand", "right_hand", "pelvis")):
        if name + "_px" not in csv.c:
            continue
        p, q = csv.index(name, "p"), csv.index(name, "q")
        rows[:, p] += rng.normal(0.0, NOISE_POSITION[k], (len(rows), 3))
        w = rng.normal(0.0, NOISE_ORIENTATION, (len(rows), 3))  # small rotation vectors, world frame
        a = np.linalg.norm(w, axis=1, keepdims=True)
        d = np.concatenate([np.where(a > 0, w / np.maximum(a, 1e-12), 0) * np.sin(a / 2), np.cos(a / 2)], axis=1)
        rows[:, q] = _qmul(d, rows[:, q])
    csv.write(path)


def controllers_on_a_table(path, seconds=TABLE_SECONDS, pickup=PICKUP_SECONDS, rate=72.0):
    """Prepends to a tracker CSV `seconds` of its first sample's headset (and belt) held, with both
    controllers lying flat on a table (a quarter turn about the world X axis from their first
    orientation) 0.45 m ahead of the headset and 0.15 m to each side at 0.76 m, then a smoothstep
    pick-up of `pickup` s to their first sample; the session's own samples follow, time-shifted."""
    csv = _TrackerCsv(path)
    r0 = csv.rows[0]
    head = r0[csv.index("head", "p")]
    fwd = csv.forward(r0)
    right = np.array([-fwd[2], 0.0, fwd[0]])
    flat = np.array([np.sin(np.pi / 4), 0.0, 0.0, np.cos(np.pi / 4)])
    n_table, n_pick = int(round(seconds * rate)), int(round(pickup * rate))
    pre = np.repeat(r0[None], n_table + n_pick, axis=0)
    a = np.clip((np.arange(n_table + n_pick) - n_table + 1) / (n_pick + 1), 0, 1)[:, None]
    a = a * a * (3 - 2 * a)
    for side, sign in (("left_hand", -1), ("right_hand", 1)):
        P, Q = csv.index(side, "p"), csv.index(side, "q")
        tp = head + 0.45 * fwd + sign * 0.15 * right
        tp[1] = 0.76
        tq = _qmul(flat, r0[Q])
        q0 = r0[Q] * np.sign(np.dot(tq, r0[Q]))
        pre[:, P] = (1 - a) * tp + a * r0[P]
        q = (1 - a) * tq + a * q0
        pre[:, Q] = q / np.linalg.norm(q, axis=1, keepdims=True)
    csv.prepend(pre, rate)
    csv.write(path)


def seated_start(path, seconds=SEATED_SECONDS, rise=STANDUP_SECONDS, drop=0.42, rate=72.0):
    """Prepends to a tracker CSV `seconds` of the user seated, then a smoothstep stand-up of `rise` s to
    its first sample: the headset `drop` m lower and 0.1 m ahead (4 mm of sideways sway at 0.3 Hz),
    a belt drop + 0.05 m lower, the controllers on the lap (0.3 m ahead of their first position,
    0.62 m high, as held); the session's own samples follow, time-shifted."""
    csv = _TrackerCsv(path)
    r0 = csv.rows[0]
    fwd = csv.forward(r0)
    n_seat, n_up = int(round(seconds * rate)), int(round(rise * rate))
    pre = np.repeat(r0[None], n_seat + n_up, axis=0)
    a = np.clip((np.arange(n_seat + n_up) - n_seat + 1) / (n_up + 1), 0, 1)[:, None]
    a = a * a * (3 - 2 * a)  # 0 seated, 1 standing
    sway = 0.004 * np.sin(2 * np.pi * 0.3 * np.arange(n_seat + n_up) / rate)[:, None] * np.array([1.0, 0.0, 0.0])
    seat = {"head": (0.10 * fwd - np.array([0.0, drop, 0.0])), "pelvis": -np.array([0.0, drop + 0.05, 0.0])}
    for name in ("head", "pelvis", "left_hand", "right_hand"):
        if f"{name}_px" not in csv.c:
            continue
        P = csv.index(name, "p")
        if name in seat:
            low = r0[P] + seat[name] + (sway if name == "head" else 0.0)
        else:
            low = np.repeat((r0[P] + 0.30 * fwd)[None], len(pre), axis=0)
            low[:, 1] = 0.62
        pre[:, P] = (1 - a) * low + a * r0[P]
    csv.prepend(pre, rate)
    csv.write(path)


def _qrot(q, v):
    """v rotated by unit quaternions q [..., 4] (x y z w)."""
    u, w = q[..., :3], q[..., 3:]
    t = 2 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def look_down_at_start(path, degrees=LOOKDOWN_DEGREES, seconds=LOOKDOWN_SECONDS, lookup=LOOKUP_SECONDS):
    """Pitches a tracker CSV's headset down by `degrees` about the head joint for its first `seconds`,
    then back to the session's own in a smoothstep of `lookup` s: a user who looks down at the
    controllers while standing at the start (the devices session's stand), then looks up. The head
    joint is the headset less the device model's eye offset; the other trackers are unchanged."""
    csv = _TrackerCsv(path)
    t = csv.rows[:, 0] - csv.rows[0, 0]
    a = np.clip((seconds + lookup - t) / lookup, 0.0, 1.0)
    a = a * a * (3 - 2 * a)  # 1 looking down, 0 the session's own
    P, Q = csv.index("head", "p"), csv.index("head", "q")
    q = csv.rows[:, Q] / np.linalg.norm(csv.rows[:, Q], axis=1, keepdims=True)
    joint = csv.rows[:, P] - _qrot(q, EYE_OPENXR)
    half = -0.5 * np.radians(degrees) * a  # about the headset's +X (right): -Z ahead turns down
    q2 = _qmul(q, np.stack([np.sin(half), 0 * half, 0 * half, np.cos(half)], axis=-1))
    csv.rows[:, Q] = q2
    csv.rows[:, P] = joint + _qrot(q2, EYE_OPENXR)
    csv.write(path)


def swap_hand_columns(path):
    """Exchanges the left and right controllers of a tracker CSV by renaming its header's columns."""
    with open(path) as f:
        lines = f.readlines()
    i = next(k for k, l in enumerate(lines) if not l.startswith("#"))
    lines[i] = lines[i].replace("left_hand", "@").replace("right_hand", "left_hand").replace("@", "right_hand")
    with open(path, "w") as f:
        f.writelines(lines)


def mode_inputs(mode, val_dir, every, tmp):
    """(source files, demo options, truth files) of a mode."""
    files = sorted(glob.glob(os.path.join(val_dir, "*.bvh")))[::every]
    if mode == "nominal":
        return files, [], files
    if mode == "devices":
        return files, DEVICES, files
    if mode in ("csv", "csvstop"):  # the user walks from the first frame and stands half-way through the clip
        return files, ["--devices"], files
    if mode in ("swapped", "noisy", "table", "seated", "lookdown"):
        return files, DEVICES, files
    if mode == "cmu":
        return [f for f in CMU if os.path.exists(f)], [], [f for f in CMU if os.path.exists(f)]
    from . import bodies
    d = os.path.join(tmp, mode)
    if not os.path.isdir(d):
        bodies.main([val_dir, d, "--preset", mode, "--every", str(every)])
    f2 = sorted(glob.glob(os.path.join(d, "*.bvh")))
    return f2, DEVICES, f2


def double_support_near_half(path):
    """The time (s) of the frame nearest the clip's middle where both toes are in
    contact (contact_labels); the middle itself when there is none."""
    c = Clip(path)
    both = np.flatnonzero(contact_labels(c, c.floor()).min(axis=1) > 0)
    mid = c.frames // 2
    f = int(both[np.argmin(np.abs(both - mid))]) if len(both) else mid
    return f / c.fps


def module_run(sb, src, model, opts, trackers_out=""):
    """(0, positions [n, 12 ROLES, 3]) of one run through the Python module, the rows and numbers the
    demo's output BVH would hold (pymod.Run.bvh_positions), or (1, error) where the demo fails."""
    try:
        kw = pymod.demo_options(opts)
        kw.setdefault("model", model)
        r = pymod.run_clip(sb, src, trackers_out=trackers_out, **kw)
    except (ValueError, OSError) as e:
        return 1, str(e)
    P = r.bvh_positions()
    return 0, P[:, [r.pipe.roles[k] for k in ROLES]]


def evaluate(demo, val_dir, mode, model, every, extra, tmp, per_clip=None, sb=None):
    """One mode and model over the clips; sb (the sparsebody module): run in-process instead of the
    demo subprocess (same inputs, same rows, the BVH's print rounding aside)."""
    src, opts, truth = mode_inputs(mode, val_dir, every, tmp)
    tot, fails = {}, []
    for ci, (s, t) in enumerate(zip(src, truth)):
        out = os.path.join(tmp, "out.bvh")
        hold = None
        opts_c = list(opts)
        if "--devices" in opts_c:
            opts_c += ["--device-seed", str(1000 + ci)]  # a different user and devices per clip
            if "--devices-stand" in opts_c:
                hold = (float(opts_c[opts_c.index("--devices-stand") + 1]), 2.5)
            if mode == "table":  # the table and the pick-up hold the first frame too
                hold = (0.0, 2.5 + TABLE_SECONDS + PICKUP_SECONDS)
            if mode == "seated":  # so do the seat and the stand-up (the clip does not sit: not compared)
                hold = (0.0, 2.5 + SEATED_SECONDS + STANDUP_SECONDS)
        csv = os.path.join(tmp, "session.csv")
        if mode in ("csv", "csvstop"):
            half = double_support_near_half(s) if mode == "csvstop" else 0.5 * Clip(s).frames / 30.0
            opts_c += ["--devices-stand", f"{half:.3f}"]
            hold = (half, 2.5)
        if sb is not None:
            if mode in CSV_MODES:
                kw = pymod.demo_options(opts_c)
                sb.read_input(s, devices=True, device_seed=kw["device_seed"], devices_stand=kw["devices_stand"],
                              trackers_out=csv)
                if mode == "swapped":
                    swap_hand_columns(csv)
                if mode == "noisy":
                    add_tracking_noise(csv, 1000 + ci)
                if mode == "table":
                    controllers_on_a_table(csv)
                if mode == "seated":
                    seated_start(csv)
                if mode == "lookdown":
                    look_down_at_start(csv)
                rc, res = module_run(sb, csv, model, extra)
            else:
                rc, res = module_run(sb, s, model, opts_c + extra)
            if rc != 0:
                fails.append((s, [res]))
                continue
            m = compare_positions(res, t, hold=hold)
        else:
            if mode in CSV_MODES:
                rc, log = run_demo(demo, s, os.path.join(tmp, "unused.bvh"), model, opts_c + extra, trackers_out=csv)
                if rc != 0:
                    fails.append((s, log.strip().splitlines()[-1:]))
                    continue
                if mode == "swapped":
                    swap_hand_columns(csv)
                if mode == "noisy":
                    add_tracking_noise(csv, 1000 + ci)
                if mode == "table":
                    controllers_on_a_table(csv)
                if mode == "seated":
                    seated_start(csv)
                if mode == "lookdown":
                    look_down_at_start(csv)
                rc, log = run_demo(demo, csv, out, model, extra)
            else:
                rc, log = run_demo(demo, s, out, model, opts_c + extra)
            if rc != 0:
                fails.append((s, log.strip().splitlines()[-1:]))
                continue
            m = compare(out, t, hold=hold)
        if m is None:
            continue
        if per_clip is not None:
            per_clip.append({"clip": os.path.basename(t), "mode": mode, "model": model,
                             **{k: (v[0] / v[1] if v[1] else None) for k, v in m.items()}})
        for k, (a, b) in m.items():
            x = tot.setdefault(k, [0.0, 0])
            x[0] += a
            x[1] += b
    res = {k: (a / b if b else float("nan")) for k, (a, b) in tot.items()}
    res["frames"] = tot.get("frames", [0, 0])[0]
    res["clips"] = len(src) - len(fails)
    res["failed"] = len(fails)
    return res, fails


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    p = argparse.ArgumentParser(prog="weights_tool.offdist", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("paths", nargs="+", metavar="PATH",
                   help="[DEMO] VALIDATION_DIR: the demo binary (needed for --runner demo) and the validation folder")
    p.add_argument("--runner", choices=["auto", "module", "demo"], default="auto",
                   help="auto: the sparsebody Python module when importable, else the demo subprocess")
    p.add_argument("--plots", default=None, help="folder for PNG figures of each model's first clip (module runner)")
    p.add_argument("--modes", nargs="+", default=["nominal", "devices", "s155", "s190", "longlegs", "shortlegs",
                                                   "csv", "cmu"])
    p.add_argument("--models", nargs="+", default=["lobstr", "n3p"])
    p.add_argument("--every", type=int, default=5)
    p.add_argument("--json", default=None)
    p.add_argument("--tmp", default=None, help="folder for the retargeted clips and outputs (kept)")
    a = p.parse_args(argv)
    if len(a.paths) > 2:
        p.error("at most two paths: [DEMO] VALIDATION_DIR")
    a.demo, a.val_dir = (a.paths[0], a.paths[1]) if len(a.paths) == 2 else (None, a.paths[0])
    sb = None if a.runner == "demo" else pymod.load(required=a.runner == "module" or a.demo is None)
    if sb is not None:
        try:
            pymod.demo_options(extra)
        except ValueError as e:  # an option only the demo has: use it if we have it
            if a.runner == "module" or a.demo is None:
                p.error(str(e))
            sb = None
    print(f"runner  {'the sparsebody Python module (in-process)' if sb else 'the demo subprocess ' + a.demo}")
    tmp = a.tmp or tempfile.mkdtemp(prefix="offdist")
    os.makedirs(tmp, exist_ok=True)
    results, clips = [], []
    print(f"{'model':7s} {'mode':10s} {'clips':>5s} {'MPJPE':>7s} {'moving':>7s} {'lower':>7s} {'toe':>7s} {'head':>7s} "
          f"{'skate':>7s} {'still':>7s} {'jitter':>7s}   (cm, cm/s, km/s^3)")
    for model in a.models:
        for mode in a.modes:
            r, fails = evaluate(a.demo, a.val_dir, mode, model, a.every, extra, tmp, clips, sb=sb)
            r.update(model=model, mode=mode)
            results.append(r)
            c = lambda k: 100 * r.get(k, float("nan"))
            print(f"{model:7s} {mode:10s} {r['clips']:5d} {c('mpjpe'):7.2f} {c('moving'):7.2f} {c('lower'):7.2f} {c('toe'):7.2f} "
                  f"{c('head'):7.2f} {c('skate'):7.2f} {c('still_feet'):7.2f} {r.get('jitter', float('nan')):7.2f}" +
                  (f"   {len(fails)} failed: {fails[0]}" if fails else ""), flush=True)
    if a.plots and sb is not None:
        from . import plots
        first = sorted(glob.glob(os.path.join(a.val_dir, "*.bvh")))[:1]
        for model in a.models:
            for f in first:
                kw = dict(pymod.demo_options(extra), model=model)
                for png in plots.plot_clip(sb, f, os.path.join(a.plots, model), **kw):
                    print(f"wrote   {png}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"summary": results, "clips": clips, "demo_options": extra,
                       "runner": "module" if sb else "demo"}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
