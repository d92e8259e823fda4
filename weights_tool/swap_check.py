"""Controllers held in the other hands (include/sparsebody/trackers/controller_swap.hpp), measured on
the validation split: each clip's device session (the offdist `devices` stream: 72 Hz, the user's own
offsets, jitter, losses, a 2.5 s stand first) is written as a tracker CSV twice, once as recorded and
once with its left / right hand columns exchanged, and both are run through the same pipeline. The
output of the swapped session is compared with the right-way-round one (not with the mocap: this
isolates what the swap costs), over every joint and over the hands, on all frames and from --after
seconds on, with the check on and off (sparsebody.create(controller_swap=False)).

  /usr/bin/python3 -m weights_tool.swap_check VALIDATION_DIR [--every 5] [--after 3] [--models lobstr n3p]
"""
import argparse
import glob
import os
import shutil
import tempfile

import numpy as np

from . import pymod
from .offdist import swap_hand_columns


def measure(sb, files, model, check, after, tmp):
    acc = {k: [0.0, 0] for k in ("all", "hands", "all_after", "hands_after")}
    found = 0
    a_csv, b_csv = os.path.join(tmp, "a.csv"), os.path.join(tmp, "b.csv")
    for ci, f in enumerate(files):
        sb.read_input(f, devices=True, device_seed=1000 + ci, devices_stand=0.0, trackers_out=a_csv)  # offdist's seeds
        shutil.copyfile(a_csv, b_csv)
        swap_hand_columns(b_csv)
        ra = pymod.run_clip(sb, a_csv, model=model)
        rb = pymod.run_clip(sb, b_csv, model=model, controller_swap=check)
        found += rb.pipe.controller_swaps > 0
        ok = ra.out["has_output"] & rb.out["has_output"]
        t = ra.out["time"] - ra.inp["time"][0]
        d = np.linalg.norm(ra.out["position"] - rb.out["position"], axis=-1)  # [T, J] metres
        hands = [ra.pipe.roles["hand_l"], ra.pipe.roles["hand_r"]]
        for key, m in (("", ok), ("_after", ok & (t >= after))):
            acc["all" + key][0] += d[m].sum()
            acc["all" + key][1] += d[m].size
            acc["hands" + key][0] += d[m][:, hands].sum()
            acc["hands" + key][1] += d[m][:, hands].size
    return found, {k: 100 * a / max(b, 1) for k, (a, b) in acc.items()}


def main(argv=None):
    p = argparse.ArgumentParser(prog="weights_tool.swap_check", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("val_dir")
    p.add_argument("--every", type=int, default=5)
    p.add_argument("--after", type=float, default=3.0, help="s: the second figures count frames from here on")
    p.add_argument("--models", nargs="+", default=["lobstr", "n3p"])
    a = p.parse_args(argv)
    sb = pymod.load(required=True)
    files = sorted(glob.glob(os.path.join(a.val_dir, "*.bvh")))[::a.every]
    with tempfile.TemporaryDirectory() as tmp:
        for model in a.models:
            for check in (True, False):
                found, r = measure(sb, files, model, check, a.after, tmp)
                print(f"{model:7s} check {'on ' if check else 'off'}  found in {found}/{len(files)} clips; swapped against "
                      f"right-way-round output, cm: every joint {r['all']:.2f}, hands {r['hands']:.2f}; from {a.after:g} s on: "
                      f"every joint {r['all_after']:.2f}, hands {r['hands_after']:.2f}", flush=True)


if __name__ == "__main__":
    main()
