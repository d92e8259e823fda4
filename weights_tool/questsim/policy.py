"""Random-weight QuestSim policy (MLP [400, 300, 200], tanh on every layer, kind "questsim_policy") and
its reference evaluation. Trained policies are not shipped; these files exist for parity tests and
benchmarks. The input normalisation written with the weights scales the foot forces by the body
weight of a 63 kg avatar (~618 N) and leaves everything else as is, so random weights see inputs of
order 1 (and the C++ normalisation path is exercised). The output layer is scaled by `output_gain`
(0.01, the policy-head gain PPO implementations initialise with): an untrained policy's torques are
then a few N m. With full-range outputs (|a| ~ 1, i.e. 200 N m on every DoF) the light segments
(hands 0.4 kg, toes 0.2 kg) reach the simulator's velocity limit within one 1/72 s substep and
every step would end in the controller's reset; a trained policy does not do that.
"""
import numpy as np
import torch

from .. import golden, nets
from ..format import read_weights, write_weights
from .layout import layout

HIDDEN = (400, 300, 200)


def make_policy(bodies, joint_dofs, future, seed, output_gain=0.01):
    L = layout(bodies, joint_dofs, future)
    model = golden.make_model(
        lambda: nets.MLPPolicy([L["size"], *HIDDEN, joint_dofs], "tanh", "tanh", "questsim_policy"), seed)
    with torch.no_grad():  # keep the values exactly representable in float32
        for p in model.layers[-1].parameters():
            p.copy_((p * output_gain).float())
    mean = np.zeros(L["size"], dtype=np.float32)
    std = np.ones(L["size"], dtype=np.float32)
    std[L["f"]:L["f"] + 6] = 618.0
    return model, {"input_mean": mean, "input_std": std}


def write_policy(path, bodies, joint_dofs, future=6, seed=7, output_gain=0.01):
    model, norm = make_policy(bodies, joint_dofs, future, seed, output_gain)
    L = layout(bodies, joint_dofs, future)
    meta = {"frame_rate": 36, "paper": "QuestSim (Winkler et al. 2022), Appendix A", "random_weights": True, "seed": seed, "output_gain": output_gain,
            "bodies": bodies, "joint_dofs": joint_dofs, "future_frames": future,
            "output": "tanh in [-1, 1], times 200 N m = joint torques"}
    write_weights(path, nets.export_state_dict(model), "questsim_policy", L["size"], joint_dofs, meta=meta,
                  normalization=norm)


def load_policy(path):
    """MLPPolicy with the file's weights (float64) and its normalisation (float64 numpy)."""
    doc, tensors, norm = read_weights(path)
    n_in, n_out = doc["meta"]["input_size"], doc["meta"]["output_size"]
    model = nets.MLPPolicy([n_in, *HIDDEN, n_out], "tanh", "tanh", "questsim_policy").double().eval()
    model.load_state_dict({k: torch.from_numpy(v) for k, v in tensors.items()})
    return model, norm


def run_policy(model, norm, x, dtype):
    """Policy output for one observation (numpy float64) in torch `dtype`, normalisation included."""
    x = np.asarray(x, dtype=np.float64)
    if norm:
        x = (x - norm["input_mean"]) / norm["input_std"]
    m = model.to(dtype)
    with torch.no_grad():
        y, _ = m(torch.from_numpy(x).to(dtype)[None])
    return y[0].double().numpy()
