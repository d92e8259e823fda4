"""python3 -m weights_tool.n3p_physics reference IN.json OUT_DIR [--seed N]

Reads the raw inputs written by tests/n3p_physics/test_policy.cpp (h_ref, the character's joints,
three predicted states, joint indices), computes the policy input s (policy_input.py) and a seeded
random Neural3Points control policy pi ([1008, 256, 256, 120], ReLU, weights_tool/nets.py
MLPPolicy; RL policies are not shipped), and writes OUT_DIR/n3p_policy_random.json (weights) and
OUT_DIR/n3p_policy_reference.json ({"s": [...], "u": pi(s) in float32})."""
import argparse
import json
import os

import numpy as np
import torch

from .. import format as wformat
from ..nets import MLPPolicy, export_state_dict
from . import policy_input as pi


def main(argv=None):
    ap = argparse.ArgumentParser(prog="weights_tool.n3p_physics")
    ap.add_argument("cmd", choices=["reference"])
    ap.add_argument("inp")
    ap.add_argument("out_dir")
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args(argv)
    with open(a.inp) as f:
        d = json.load(f)
    p, v = np.array(d["p"]), np.array(d["v"])
    R = np.array(d["R"]).reshape(-1, 3, 3)
    future = [(f["h"], f["g_lo"], f["g_up"]) for f in d["future"]]
    s = pi.policy_input(d["h_ref"], p, v, R, future, d["lower"], d["upper"])
    torch.manual_seed(a.seed)
    net = MLPPolicy([pi.POLICY_IN, 256, 256, pi.POLICY_OUT], "relu", "identity", kind="n3p_policy")
    os.makedirs(a.out_dir, exist_ok=True)
    wformat.write_weights(os.path.join(a.out_dir, "n3p_policy_random.json"), export_state_dict(net), "n3p_policy",
                          pi.POLICY_IN, pi.POLICY_OUT, meta={"note": "random seeded policy for parity tests, not trained"})
    with torch.no_grad():
        u = net(torch.tensor(s, dtype=torch.float32)[None])[0][0].numpy()
    with open(os.path.join(a.out_dir, "n3p_policy_reference.json"), "w") as f:
        json.dump({"s": s.tolist(), "u": u.astype(np.float64).tolist()}, f)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
