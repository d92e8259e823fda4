"""Learning curve of a Neural3Points training log (the lines `weights_tool.n3p train` prints):
training loss every 25 fine-tuning iterations and validation loss every 200, as a PNG.

  /usr/bin/python3 -m weights_tool.n3p.curve LOG [LOG ...] -o curve.png [--title T]

Several logs (a run and its resumptions) are drawn one after the other on one iteration axis."""
import argparse
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TRAIN = re.compile(r"^\[finetune\] it (\d+) \S+ loss ([0-9.]+)")
VAL = re.compile(r"^\[finetune\] VAL it (\d+) ([0-9.]+)")
START = re.compile(r"^\[finetune\] start val loss ([0-9.]+)")


def read(paths):
    """(train [(it, loss)], val [(it, loss)]) over the logs, iterations continued across them."""
    train, val, base = [], [], 0
    for p in paths:
        last = 0
        with open(p) as f:
            for line in f:
                if m := START.match(line):
                    val.append((base, float(m.group(1))))
                elif m := TRAIN.match(line):
                    last = int(m.group(1))
                    train.append((base + last, float(m.group(2))))
                elif m := VAL.match(line):
                    last = int(m.group(1))
                    val.append((base + last, float(m.group(2))))
        base += last
    return train, val


def main(argv=None):
    ap = argparse.ArgumentParser(prog="weights_tool.n3p.curve", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("logs", nargs="+")
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--title", default="Neural3Points fine-tuning (G_sig + G_lo, G_up frozen)")
    a = ap.parse_args(argv)
    train, val = read(a.logs)
    if not val:
        raise SystemExit(f"no [finetune] lines in {a.logs}")
    fig, ax = plt.subplots(figsize=(7, 4))
    if train:
        ax.plot(*zip(*train), lw=0.6, alpha=0.5, label="training batch loss")
    ax.plot(*zip(*val), "o-", ms=3, label="validation loss (the checkpoint kept is its minimum)")
    best = min(val, key=lambda x: x[1])
    ax.annotate(f"best {best[1]:.3f} at it {best[0]}", best, textcoords="offset points", xytext=(-60, 20),
                arrowprops=dict(arrowstyle="->"))
    ax.set_xlabel("fine-tuning iteration (batch 32 x 60 frames)")
    ax.set_ylabel("loss (Eqs. 3-6 + FK)")
    ax.set_ylim(0, max(v for _, v in val) * 1.6)
    ax.set_title(a.title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out, dpi=100)
    print(f"wrote {a.out}: {len(train)} training points, {len(val)} validation points, best {best[1]:.4f} at it {best[0]}")


if __name__ == "__main__":
    main()
