"""Runs the C++ pipeline (the demo's: contact IK, upper-body IK) over a BVH folder and averages the
demo's metrics, weighted by frames.
  /usr/bin/python3 -m weights_tool.lobstr.cpp_eval [build/examples/sparsebody_demo] /tmp/val [--every 1]
        [--runner auto|module|demo] [-- demo options]
In-process through the sparsebody Python module when it is importable (the demo's own Metrics on the
same rows: sparsebody.demo_metrics), else the demo as a subprocess with its printed metrics parsed;
the first line says which. The two agree to the printed 2 decimals.
"""
import glob
import os
import re
import subprocess
import sys

KEYS = {"contact accuracy": "contact", "lower-body rot. error": "rot", "toe position error": "toe",
        "MPJPE (12 joints)": "mpjpe", "MPJPE lower body": "mpjpe_lower", "jitter (lower body)": "jitter",
        "foot skating": "skate"}


def module_metrics(sb, f, extra):
    """The demo's metrics of one clip through the module (dict of KEYS' values and frames)."""
    from .. import pymod
    kw = pymod.demo_options(extra)
    r = pymod.run_clip(sb, f, **kw)
    m = sb.demo_metrics(r.pipe, r.out, f, devices=kw.get("devices", False), device_seed=kw.get("device_seed", 0),
                        devices_stand=kw.get("devices_stand", -1.0))
    return {"mpjpe_lower": m["mpjpe_lower"], **{k: m[k] for k in KEYS.values() if k in m and m[k] is not None}}, m["frames"]


def main(argv):
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    every = 1
    if "--every" in argv:
        i = argv.index("--every")
        every = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    runner = "auto"
    if "--runner" in argv:  # auto (the module when importable), module, demo
        i = argv.index("--runner")
        runner = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    demo, folder = (argv[0], argv[1]) if len(argv) >= 2 else (None, argv[0])
    from .. import pymod
    sb = None if runner == "demo" else pymod.load(required=demo is None or runner == "module")
    if sb is not None:
        try:
            pymod.demo_options(extra)
        except ValueError:
            if demo is None:
                raise
            sb = None  # a demo option the module does not reproduce
    print(f"runner  {'the sparsebody Python module (in-process)' if sb else 'the demo subprocess ' + demo}")
    files = sorted(glob.glob(os.path.join(folder, "*.bvh")))[::every]
    tot, n = {}, 0
    for f in files:
        if sb is not None:
            try:
                vals, w = module_metrics(sb, f, extra)
            except (ValueError, OSError):
                continue  # where the demo exits with an error
            if w == 0:
                continue
            for k, v in vals.items():
                tot[k] = tot.get(k, 0.0) + v * w
            n += w
            continue
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
