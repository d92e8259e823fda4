"""Runs the C++ demo (the whole pipeline: contact IK, upper-body IK) over a BVH folder and averages
its printed metrics, weighted by frames.
  /usr/bin/python3 -m weights_tool.lobstr.cpp_eval build/examples/sparsebody_demo /tmp/val [--every 1] [-- demo options]
"""
import glob
import os
import re
import subprocess
import sys

KEYS = {"contact accuracy": "contact", "lower-body rot. error": "rot", "toe position error": "toe",
        "MPJPE (12 joints)": "mpjpe", "MPJPE lower body": "mpjpe_lower", "jitter (lower body)": "jitter",
        "foot skating": "skate"}


def main(argv):
    demo, folder = argv[0], argv[1]
    every = 1
    extra = []
    if "--every" in argv:
        every = int(argv[argv.index("--every") + 1])
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
    files = sorted(glob.glob(os.path.join(folder, "*.bvh")))[::every]
    tot, n = {}, 0
    for f in files:
        out = subprocess.run([demo, f, "-o", "/tmp/cpp_eval.bvh", "--quiet"] + extra, capture_output=True, text=True).stdout
        m = re.search(r"metrics vs the input clip \((\d+) frames\)", out)
        if not m:
            continue
        w = int(m.group(1))
        for line in out.splitlines():
            for label, k in KEYS.items():
                if line.strip().startswith(label):
                    v = re.findall(r"[-+]?\d+\.\d+", line)
                    if v:
                        tot[k] = tot.get(k, 0.0) + float(v[0]) * w
        n += w
    print(f"C++ pipeline ({' '.join(extra) or 'streaming, contact IK'}) on {len(files)} clips, {n} frames of {folder}")
    for label, k in KEYS.items():
        if k in tot:
            print(f"  {label:24s} {tot[k] / n:8.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])
