"""Bodies of other sizes for off-distribution measures (issue 12): a BVH clip retargeted to a scaled
body by scaling its segment lengths, written as a new BVH (same hierarchy, same rotations).

Scale factors, as weights_tool/devices.py: every segment by stature / the standard performer's stature,
then legs (thigh, shin, foot), torso (spine to head, clavicles, hip width) and arms (upper arm,
forearm) by their own ratios. The root chain (the pelvis height and the ground track) follows the legs,
so the feet stay on the floor and the stride matches the legs.

  /usr/bin/python3 -m weights_tool.bodies IN_DIR OUT_DIR --stature 1.90 [--leg 1.08 --torso 0.95 --arm 1]
"""
import argparse
import glob
import os
import re
import sys

import numpy as np

from .devices import ARM, LEG, STANDARD_STATURE, TORSO
from .lobstr import bvh

PRESETS = {  # name: (stature m, leg, torso, arm)
    "s155": (1.55, 1.0, 1.0, 1.0),
    "s190": (1.90, 1.0, 1.0, 1.0),
    "longlegs": (1.75, 1.08, 0.93, 1.0),
    "shortlegs": (1.70, 0.92, 1.07, 1.0),
    "s172": (1.72, 1.0, 1.0, 1.0),
    "longarms": (1.72, 1.0, 1.0, 1.08),
    "shortarms": (1.72, 1.0, 1.0, 0.92),
}


def factors(b, stature, leg=1.0, torso=1.0, arm=1.0):
    """Per-joint scale of the joint's own offset / translation channels."""
    k = stature / STANDARD_STATURE
    f = np.full(len(b.names), k)
    for names, r in ((LEG, leg), (TORSO, torso), (ARM, arm)):
        for n in names:
            if n in b.names:
                f[b.index(n)] = k * r
    j = b.index("Hips")
    while j >= 0:
        f[j] = k * leg
        j = b.parents[j]
    return f


def scale_text(text, source, stature, leg=1.0, torso=1.0, arm=1.0):
    b = bvh.parse(text, source)
    f = factors(b, stature, leg, torso, arm)
    head, motion = text.split("MOTION", 1)
    out, stack, joint = [], [], None
    for line in head.splitlines():
        s = line.strip()
        m = re.match(r"(ROOT|JOINT)\s+(\S+)", s)
        if m:
            joint = b.index(m.group(2))
        elif s.startswith("End"):
            joint = ("end", joint)
        elif s.startswith("{"):
            stack.append(joint)
        elif s.startswith("}"):
            stack.pop()
            joint = stack[-1] if stack else None
        elif s.startswith("OFFSET"):
            cur = stack[-1]
            # an End Site belongs to its joint's segment
            fj = f[cur[1]] if isinstance(cur, tuple) else f[cur]
            v = np.array([float(x) for x in s.split()[1:4]]) * fj
            line = line[:len(line) - len(line.lstrip())] + "OFFSET " + " ".join(f"{x:.6g}" for x in v)
        out.append(line)
    M = b.motion.copy()
    c = 0
    for j, chans in enumerate(b.channels):
        for name in chans:
            if name.lower().endswith("position"):
                M[:, c] *= f[j]
            c += 1
    lines = motion.strip().splitlines()
    hdr = [l for l in lines[:3] if l.startswith("Frames") or l.startswith("Frame Time")]
    body = "\n".join(" ".join(f"{x:.6g}" for x in row) for row in M)
    return "\n".join(out) + "\nMOTION\n" + "\n".join(hdr) + "\n" + body + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(prog="weights_tool.bodies", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("in_dir")
    p.add_argument("out_dir")
    p.add_argument("--preset", choices=sorted(PRESETS))
    p.add_argument("--stature", type=float, default=STANDARD_STATURE)
    p.add_argument("--leg", type=float, default=1.0)
    p.add_argument("--torso", type=float, default=1.0)
    p.add_argument("--arm", type=float, default=1.0)
    p.add_argument("--every", type=int, default=1)
    a = p.parse_args(argv)
    st, leg, torso, arm = PRESETS[a.preset] if a.preset else (a.stature, a.leg, a.torso, a.arm)
    os.makedirs(a.out_dir, exist_ok=True)
    files = sorted(glob.glob(os.path.join(a.in_dir, "*.bvh")))[::a.every]
    for f in files:
        with open(f) as fh:
            t = scale_text(fh.read(), f, st, leg, torso, arm)
        with open(os.path.join(a.out_dir, os.path.basename(f)), "w") as fh:
            fh.write(t)
    print(f"wrote {len(files)} clips to {a.out_dir}: stature {st:.2f} m, leg x{leg}, torso x{torso}, arm x{arm}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
