"""Pipeline evaluations of Neural3Points correction-policy snapshots against training samples.

Each input file holds one line per snapshot and validation half, as the training session's loop wrote
them: `HHMM samples N half H <n3p_physics_eval's two "physics" lines joined>`, e.g.

    2342 1392640 ... half 0 physics  MPJPE  25.71 cm (...) | foot skating 47.08 cm/s | ... falls 418 (...; 38.32 per minute of output) ...

Plots falls per minute and MPJPE (latency removed) per half against samples, one colour per run,
with the model-based controller's figures at the same residual bound as dashed lines (--baseline).

  /usr/bin/python3 -m weights_tool.n3p_physics.evals_plot OUT.png RUN=FILE [RUN=FILE ...]
      [--baseline LABEL=FALLS_PER_MIN,MPJPE_CM ...]
"""
import argparse
import re

LINE = re.compile(r"samples (\d+) half (\d) physics +MPJPE +([0-9.]+) cm.*?; ([0-9.]+) per minute of output")


def read(path):
    rows = []
    for line in open(path):
        m = LINE.search(line)
        if m:
            rows.append((int(m.group(1)), int(m.group(2)), float(m.group(3)), float(m.group(4))))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(prog="weights_tool.n3p_physics.evals_plot")
    ap.add_argument("out")
    ap.add_argument("runs", nargs="+", help="LABEL=FILE")
    ap.add_argument("--baseline", nargs="*", default=[], help="LABEL=FALLS_PER_MIN,MPJPE_CM")
    a = ap.parse_args(argv)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 4))
    for k, spec in enumerate(a.runs):
        label, path = spec.split("=", 1)
        rows = read(path)
        for half, style in ((0, "-o"), (1, "--s")):
            r = sorted(x for x in rows if x[1] == half)
            if not r:
                continue
            s = [x[0] / 1e6 for x in r]
            ax[0].plot(s, [x[3] for x in r], style, color=f"C{k}", ms=3, label=f"{label}, half {half}")
            ax[1].plot(s, [x[2] for x in r], style, color=f"C{k}", ms=3, label=f"{label}, half {half}")
    for k, spec in enumerate(a.baseline):
        label, vals = spec.split("=", 1)
        f, e = (float(v) for v in vals.split(","))
        ax[0].axhline(f, color=f"C{k + len(a.runs)}", ls=":", label=label)
        ax[1].axhline(e, color=f"C{k + len(a.runs)}", ls=":", label=label)
    ax[0].set_title("falls per minute of output (validation halves)")
    ax[1].set_title("MPJPE, latency removed (cm)")
    for x in ax:
        x.set_xlabel("training samples (M)")
        x.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.out, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    main()
