"""Command line: /usr/bin/python3 -m weights_tool {export,golden} ..."""
import argparse
import sys

import torch

from . import nets
from .format import write_weights
from .golden import write_set

FACTORIES = {
    "lobstr": lambda a: nets.LoBSTrNet(hidden=a.hidden, latent=a.latent),
    "n3p_signal": lambda a: nets.N3PPredictor(a.inputs, a.hidden, a.outputs, kind="n3p_signal"),
    "n3p_lower": lambda a: nets.N3PPredictor(a.inputs, a.hidden, a.outputs, kind="n3p_lower"),
    "n3p_upper": lambda a: nets.N3PPredictor(a.inputs, a.hidden, a.outputs, kind="n3p_upper"),
}


def main(argv=None):
    p = argparse.ArgumentParser(prog="weights_tool", description=__doc__)
    sub = p.add_subparsers(dest="cmd", required=True)
    e = sub.add_parser("export", help="write a weights JSON from a PyTorch checkpoint (state_dict .pt)")
    e.add_argument("checkpoint", help="torch.save()d state_dict, or a dict with 'state_dict' and optional "
                                      "'normalization' (input_mean/input_std/output_mean/output_std) and 'meta'")
    e.add_argument("out")
    e.add_argument("--kind", required=True, choices=sorted(FACTORIES) + ["mlp", "n3p_policy", "questsim_policy"])
    e.add_argument("--inputs", type=int)
    e.add_argument("--outputs", type=int)
    e.add_argument("--hidden", type=int, default=1024)
    e.add_argument("--latent", type=int, default=128)
    e.add_argument("--encoding", choices=["base64", "list"], default="base64")
    g = sub.add_parser("golden", help="write golden weights/vectors for the C++ parity tests")
    g.add_argument("set", choices=["small", "paper"])
    g.add_argument("out_dir")
    g.add_argument("--steps", type=int, default=1000)
    a = p.parse_args(argv)
    if a.cmd == "golden":
        names = write_set(a.set, a.out_dir, a.steps)
        print(f"wrote {len(names)} golden sets to {a.out_dir}: {', '.join(names)}")
        return 0
    ck = torch.load(a.checkpoint, map_location="cpu")
    sd = ck.get("state_dict", ck) if isinstance(ck, dict) else ck.state_dict()
    meta = ck.get("meta", {}) if isinstance(ck, dict) else {}
    norm = ck.get("normalization") if isinstance(ck, dict) else None
    if a.kind in FACTORIES:  # check the state_dict loads into the reference module (names, shapes)
        if a.kind == "lobstr":
            a.inputs, a.outputs = a.inputs or 37, 52
        m = FACTORIES[a.kind](a)
        m.load_state_dict(sd, strict=True)
    if a.inputs is None or a.outputs is None:
        p.error("--inputs and --outputs are required for this kind")
    write_weights(a.out, sd, a.kind, a.inputs, a.outputs, meta=meta, normalization=norm, encoding=a.encoding)
    print(f"wrote {a.out}: kind {a.kind}, {len(sd)} tensors")
    return 0


if __name__ == "__main__":
    sys.exit(main())
