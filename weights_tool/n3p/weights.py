"""Load exported weights files back into the reference modules (for evaluation and tests)."""
import torch

from ..format import read_weights
from .export import NORM_NAMES, SUFFIX
from .model import Sub


def load(prefix):
    """(nets [sig, lo, up], initial_state) from <prefix>_signal.json, _lower.json, _upper.json."""
    nets, init = [], None
    for name in ("sig", "lo", "up"):
        doc, tensors, norm = read_weights(prefix + SUFFIX[name])
        hidden = doc["meta"]["hidden"][name]
        s = Sub(name, hidden)
        s.net.load_state_dict({k: torch.tensor(v, dtype=torch.float32) for k, v in tensors.items()})
        for k, v in NORM_NAMES.items():
            getattr(s, k).copy_(torch.tensor(norm[v], dtype=torch.float32))
        s.eval()
        nets.append(s)
        init = doc["meta"]["initial_state"]
    return nets, init
