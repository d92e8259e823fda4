"""Plots pipeline evaluations of training snapshots: falls per minute and MPJPE against samples, one
line per run and validation half.

Each input is a text file of lines holding `samples S half H` and the evaluation's physics summary
(`n3p_physics_eval` or `questsim.evaluate`: `MPJPE X cm` and `Y per minute of output`), as the
snapshot loops of the README's training runs write them; other lines are skipped.

  /usr/bin/python3 -m weights_tool.questsim.plot_pipeline_evals OUT.png RUN5.txt RUN6.txt \\
      [--labels "run 5" "run 6"] [--baseline 26.6]
"""
import argparse
import re
import sys

ROW = re.compile(r"samples\s+(\d+)\s+half\s+(\d+)\b.*?MPJPE\s+([\d.]+)\s*cm.*?([\d.]+)\s+per minute of output")


def read_evals(path):
    """{half: [(samples, falls per minute, MPJPE cm)]} sorted by samples."""
    out = {}
    with open(path) as f:
        for line in f:
            m = ROW.search(line)
            if m:
                s, h, e, falls = int(m.group(1)), int(m.group(2)), float(m.group(3)), float(m.group(4))
                out.setdefault(h, []).append((s, falls, e))
    for rows in out.values():
        rows.sort()
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("png")
    ap.add_argument("evals", nargs="+")
    ap.add_argument("--labels", nargs="+", default=None)
    ap.add_argument("--baseline", type=float, default=None, help="falls per minute to draw as a line")
    ap.add_argument("--title", default="pipeline evaluations of training snapshots")
    a = ap.parse_args(argv)
    labels = a.labels or a.evals
    if len(labels) != len(a.evals):
        raise SystemExit(f"{len(a.evals)} files but {len(labels)} labels")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for i, (path, label) in enumerate(zip(a.evals, labels)):
        color = f"C{i % 10}"  # one colour per run; half 0 solid, half 1 dashed
        data = read_evals(path)
        if not data:
            raise SystemExit(f"{path}: no line with 'samples S half H ... MPJPE X cm ... Y per minute of output'")
        for h, rows in sorted(data.items()):
            s = [r[0] / 1e6 for r in rows]
            style = dict(color=color, ms=3, label=f"{label}, half {h}")
            ax[0].plot(s, [r[1] for r in rows], "o-" if h == 0 else "s--", **style)
            ax[1].plot(s, [r[2] for r in rows], "o-" if h == 0 else "s--", **style)
    if a.baseline is not None:
        ax[0].axhline(a.baseline, color="k", lw=0.8, ls=":", label=f"baseline {a.baseline:g}")
    ax[0].set_ylabel("falls per minute of output")
    ax[1].set_ylabel("MPJPE (cm)")
    for x in ax:
        x.set_xlabel("samples (M)")
        x.grid(alpha=0.3)
    ax[0].legend(fontsize=7)
    fig.suptitle(a.title)
    fig.tight_layout()
    fig.savefig(a.png, dpi=100)
    print(f"wrote {a.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
