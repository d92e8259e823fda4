"""Command line: /usr/bin/python3 -m weights_tool.n3p {dataset,train,average,export,evaluate,golden} ...

Reproduce the default weights (examples/weights/n3p_*.json), from the repository root:
  mkdir -p /tmp/n3p/data && tar -xJf ../shared/data/bandai-namco/train.tar.xz -C /tmp/n3p/data
  tar -xJf ../shared/data/bandai-namco/validation.tar.xz -C /tmp/n3p/data
  python3 -m weights_tool.n3p dataset /tmp/n3p/data/train /tmp/n3p/train.npz --every 2
  python3 -m weights_tool.n3p dataset /tmp/n3p/data/validation /tmp/n3p/val.npz
  python3 -m weights_tool.n3p train --train /tmp/n3p/train.npz --val /tmp/n3p/val.npz --out /tmp/n3p/n3p.pt \
      --minutes 6 12 12 20          # wall-clock budget per stage (sig, lo, up pretraining; fine-tuning)
  python3 -m weights_tool.n3p export /tmp/n3p/n3p.pt /tmp/n3p/train.npz examples/weights/n3p
  python3 -m weights_tool.n3p evaluate examples/weights/n3p /tmp/n3p/val.npz
  python3 -m weights_tool.n3p golden tests/n3p/golden --default examples/weights/n3p   # C++ parity goldens
"""
import argparse
import json
import sys


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    cmd, rest = argv[0], argv[1:]
    import torch
    torch.set_num_threads(1)  # shared CPU: one thread (train sets its own with --threads)
    if cmd == "train":
        from . import train
        return train.main(rest)
    p = argparse.ArgumentParser(prog=f"weights_tool.n3p {cmd}")
    if cmd == "dataset":
        from . import dataset
        p.add_argument("data_dir")
        p.add_argument("out")
        p.add_argument("--every", type=int, default=1)
        p.add_argument("--limit", type=int, default=None)
        p.add_argument("--device-realisations", type=int, default=0,
                       help="copies per clip on random bodies with device-realistic trackers")
        p.add_argument("--no-plain", action="store_true", help="leave out the trackers-at-the-joints copy")
        p.add_argument("--seed", type=int, default=0)
        a = p.parse_args(rest)
        dataset.build(a.data_dir, a.out, a.every, a.limit, a.device_realisations, not a.no_plain, a.seed)
    elif cmd == "export":
        from . import export, train
        from .dataset import Data
        p.add_argument("checkpoint")
        p.add_argument("train_npz", help="training arrays (for the default start state)")
        p.add_argument("prefix")
        a = p.parse_args(rest)
        nets, info = train.load(a.checkpoint)
        print("\n".join(export.export_nets(nets, a.prefix, export.initial_state(Data(a.train_npz)), info)))
    elif cmd == "evaluate":
        from . import evaluate, weights
        from .dataset import Data
        p.add_argument("prefix", help="weights prefix (…/n3p for n3p_signal.json, n3p_lower.json, n3p_upper.json)")
        p.add_argument("val_npz")
        p.add_argument("--limit", type=int, default=None)
        p.add_argument("--json", default=None, help="also write the figures here")
        p.add_argument("--dump-direct", default=None, metavar="PATH",
                       help="write the clips' trackers and ground truth for the C++ direct-mode evaluation and stop")
        a = p.parse_args(rest)
        if a.dump_direct:
            evaluate.dump_for_direct_mode(Data(a.val_npz), a.dump_direct, a.limit)
            return 0
        nets, init = weights.load(a.prefix)
        r = evaluate.report(nets, Data(a.val_npz), init, a.limit)
        if a.json:
            with open(a.json, "w") as f:
                json.dump(r, f, indent=1)
    elif cmd == "average":
        from . import train
        p.add_argument("out", help="checkpoint (.pt) to write")
        p.add_argument("checkpoints", nargs="+", help="checkpoints of one run (e.g. OUT.it600 OUT.it900 ...)")
        a = p.parse_args(rest)
        print(train.average(a.checkpoints, a.out))
    elif cmd == "golden":
        from . import golden
        p.add_argument("out_dir")
        p.add_argument("--default", default=None, metavar="PREFIX",
                       help="also write n3p_default.golden.json for the weights at PREFIX (e.g. examples/weights/n3p)")
        a = p.parse_args(rest)
        print(golden.write(a.out_dir))
        if a.default:
            import os
            print(golden.write_default(a.default, os.path.join(a.out_dir, "n3p_default.golden.json")))
    else:
        print(f"unknown command {cmd!r}\n{__doc__}")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
