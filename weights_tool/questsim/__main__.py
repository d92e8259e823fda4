"""Command line: /usr/bin/python3 -m weights_tool.questsim {policy,reference} ...

  policy --bodies 21 --joint-dofs 48 [--future 6] [--seed 7] [--output-gain 0.01] --out questsim_policy.json
      a random-weight QuestSim policy in the sparsebody weights format (kind "questsim_policy")
  reference --case case.json --weights questsim_policy.json --out reference.json
      for every state in case.json (written by tests/questsim/test_parity.cpp: the model JSON, q, v,
      contact forces, sensor window, height), the torch observation (float64) and the policy output
      on it in float64 and float32
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
    torch.set_num_threads(1)
    p = argparse.ArgumentParser(prog=f"weights_tool.questsim {cmd}")
    if cmd == "policy":
        from .policy import write_policy
        p.add_argument("--bodies", type=int, required=True)
        p.add_argument("--joint-dofs", type=int, required=True)
        p.add_argument("--future", type=int, default=6)
        p.add_argument("--seed", type=int, default=7)
        p.add_argument("--output-gain", type=float, default=0.01)
        p.add_argument("--out", required=True)
        a = p.parse_args(rest)
        write_policy(a.out, a.bodies, a.joint_dofs, a.future, a.seed, a.output_gain)
    elif cmd == "reference":
        from .observation import observation
        from .policy import load_policy, run_policy
        p.add_argument("--case", required=True)
        p.add_argument("--weights", required=True)
        p.add_argument("--out", required=True)
        a = p.parse_args(rest)
        with open(a.case) as f:
            case = json.load(f)
        model, norm = load_policy(a.weights)
        out = {"observations": [], "actions64": [], "actions32": []}
        for c in case["states"]:
            o = observation(case["model"], c["q"], c["v"], c["contacts"], c["user"], c["height"], case["future"])
            x = o.numpy()
            out["observations"].append(x.tolist())
            out["actions64"].append(run_policy(model, norm, x, torch.float64).tolist())
            out["actions32"].append(run_policy(model, norm, x, torch.float32).tolist())
        with open(a.out, "w") as f:
            json.dump(out, f)
    else:
        print(f"unknown command {cmd!r}\n{__doc__}")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
