"""Control steps per second of the batched QuestSim training environment with 1 and 2 threads
(issue 14's measure; the trainer's own rate is lower: it also runs the policy and PPO).

  SPARSEBODY_PYMOD_DIR=build/python /usr/bin/python3 -m weights_tool.questsim.throughput TRAIN_DIR \\
      [--envs 128] [--steps 400] [--repeats 3] [--threads 1 2]

Actions are small random torques (std 0.05, the trainer's initial exploration), so characters fall
and are reset at the rate an untrained policy gives; the figure is the median over repeats, each
after a warm-up of 50 steps. --task n3p measures the Neural3Points correction-policy environment
instead (n3p_env.hpp: a step is one 30 Hz frame of 4 substeps; actions std 0.05 of the 0.2 rad scale)."""
import argparse
import os
import platform
import statistics
import time

import numpy as np

from .env import ROOT, load_module
from .train import pick_clips


def cpu_name():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="weights_tool.questsim.throughput", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("train_dir")
    ap.add_argument("--envs", type=int, default=128)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--clips", type=int, default=64)
    ap.add_argument("--motions", default="raise-up|wave|bye|bow|guide|call|respond|walk")
    ap.add_argument("--task", choices=("questsim", "n3p"), default="questsim")
    a = ap.parse_args(argv)
    qe = load_module()
    n3p = a.task == "n3p"
    clips = qe.load_clips(pick_clips(a.train_dir, a.motions, a.clips),
                          os.path.join(ROOT, "examples/weights/n3p_lower.json"), 30.0 if n3p else 36.0)
    Env = qe.N3PEnv if n3p else qe.Env
    rng = np.random.default_rng(0)
    print(f"CPU: {cpu_name()}, {os.cpu_count()} logical CPUs; {a.task}: {a.envs} characters, {len(clips)} clips")
    for th in a.threads:
        rates, resets = [], []
        for r in range(a.repeats):
            env = qe.N3PEnv(clips, a.envs, 1 + r) if n3p else qe.Env(clips, [1.75] * a.envs, 1 + r)
            u = (0.05 * rng.standard_normal((a.steps + 50, a.envs, Env.action_size))).astype(np.float32)
            for i in range(50):
                env.step(u[i], th)
            ended = 0
            t0 = time.perf_counter()
            for i in range(50, a.steps + 50):
                env.step(u[i], th)
                ended += int(np.count_nonzero(env.terminated) + np.count_nonzero(env.truncated))
            dt = time.perf_counter() - t0
            rates.append(a.steps * a.envs / dt)
            resets.append(ended / (a.steps * a.envs))
        print(f"threads {th}: {statistics.median(rates) / 1e3:.1f} k {'frames' if n3p else 'control steps'}/s (median of {a.repeats}: "
              f"{', '.join(f'{x / 1e3:.1f}' for x in rates)}), episodes ending on {100 * statistics.mean(resets):.1f} % of steps")


if __name__ == "__main__":
    main()
