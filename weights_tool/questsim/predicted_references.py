"""Reference clips as the physics pipeline meets them: Neural3Points direct mode's prediction of each
clip, written as the demo's output BVH (issue 14, item 4).

The correction policy's environment (`--task n3p`) tracks the clip itself, while the physics pipeline
tracks the direct-mode prediction (smoother, a crouched shuffle where the trackers do not show the
legs). Training on the predictions gives the policy the references it meets at run time. The
trackers are the demo's for a BVH (at the joints, sized by the clip's leg length), as in the
physics evaluation (`n3p_physics_eval`), so the file names, and the motion filter, stay the clip's.

  SPARSEBODY_PYMOD_DIR=build/python /usr/bin/python3 -m weights_tool.questsim.predicted_references \\
      TRAIN_DIR OUT_DIR [--motions REGEX] [--every K]
  ... weights_tool.questsim.train OUT_DIR --task n3p ...

OUT_DIR holds data-derived clips: keep it outside the repository.
"""
import argparse
import os
import sys
import time

from .. import pymod
from .train import DEFAULT_MOTIONS, pick_clips

# The predictor the physics pipeline runs by default (its controller and correction policy were tuned
# with it; examples/weights/N3P_README.md).
N3P_PHYSICS_WEIGHTS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                                   "examples", "weights", "n3p_physics")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("train_dir")
    ap.add_argument("out_dir")
    ap.add_argument("--motions", default=DEFAULT_MOTIONS, help="regex on clip names (the trainer's default)")
    ap.add_argument("--every", type=int, default=1, help="every K-th matching clip")
    a = ap.parse_args(argv)
    if a.every < 1:
        raise SystemExit(f"--every {a.every}: expected a whole number >= 1")
    sb = pymod.load(required=True)
    paths = pick_clips(a.train_dir, a.motions, 0)[::a.every]
    os.makedirs(a.out_dir, exist_ok=True)
    t0, frames = time.time(), 0
    for i, path in enumerate(paths):
        out = os.path.join(a.out_dir, os.path.basename(path))
        try:  # a bad clip stops the run with the module's one-line message (it names the file)
            run = pymod.run_clip(sb, path, "n3p", weights=N3P_PHYSICS_WEIGHTS)
            sb.write_bvh(out, run.pipe, run.out)
        except (OSError, ValueError) as e:
            raise SystemExit(str(e) if path in str(e) else f"{path}: {e}") from None
        frames += len(run.inp["time"])
        if (i + 1) % 200 == 0 or i + 1 == len(paths):
            print(f"{i + 1}/{len(paths)} clips, {frames} frames, {time.time() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
