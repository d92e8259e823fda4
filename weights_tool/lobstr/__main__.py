"""Command line: /usr/bin/python3 -m weights_tool.lobstr {prepare,train,evaluate,export,golden} ...

  prepare   BVH folders -> cached features/targets (.npz) with synthetic noisy trackers
  train     train on the cache (see train.py for options); best checkpoint by validation loss
  evaluate  Table 1 metrics (+ MPJPE, jitter, foot skating) of a checkpoint on a cache
  export    checkpoint -> weights JSON with the pipeline metadata and the data credit
  golden    parity golden for tests/pipeline (random small network, CMU clip)
"""
import argparse
import sys


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv and argv[0] == "train":
        from . import train
        return train.main(argv[1:])
    if argv and argv[0] == "evaluate":
        from . import evaluate
        return evaluate.main(argv[1:])
    p = argparse.ArgumentParser(prog="weights_tool.lobstr", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    pr = sub.add_parser("prepare")
    pr.add_argument("data_dir")
    pr.add_argument("out")
    pr.add_argument("--realisations", type=int, default=1)
    pr.add_argument("--seed", type=int, default=0)
    pr.add_argument("--offset-deg", type=float, default=0.0)
    pr.add_argument("--scale-jitter", type=float, default=0.0)
    pr.add_argument("--limit", type=int)
    pr.add_argument("--device-realisations", type=int, default=0,
                    help="extra realisations per clip on random bodies with device-realistic trackers")
    sub.add_parser("train", help="see: train --help")
    sub.add_parser("evaluate", help="see: evaluate --help")
    ex = sub.add_parser("export")
    ex.add_argument("checkpoint")
    ex.add_argument("out")
    ex.add_argument("--command", default=None, help="training command recorded in meta.training")
    go = sub.add_parser("golden")
    go.add_argument("out_dir")
    go.add_argument("--clip", default=None)
    a = p.parse_args(argv)
    if a.cmd == "prepare":
        from . import dataset
        dataset.build(a.data_dir, a.out, a.realisations, a.seed, a.limit, a.offset_deg, a.scale_jitter,
                      device_realisations=a.device_realisations)
    elif a.cmd == "export":
        from .export import export
        print("wrote", export(a.checkpoint, a.out, a.command))
    elif a.cmd == "golden":
        from . import golden
        print("wrote", *golden.write(a.out_dir, a.clip or golden.DEFAULT_CLIP))
    return 0


if __name__ == "__main__":
    sys.exit(main())
