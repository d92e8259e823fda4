"""PyTorch reference modules mirroring the C++ networks (include/sparsebody/networks, nn/).

Each module's state_dict names are exactly the tensor names the C++ network binds, and
``forward(x, h)`` runs a whole sequence x [batch, time, in] the way the C++ ``step`` runs it frame
by frame. Dropout layers (training only) are identity in eval mode.
"""
import torch
from torch import nn
import torch.nn.functional as F


class GroupSoftmax(nn.Module):
    """Softmax over consecutive groups of `group` values (C++ nn::Softmax<group>)."""

    def __init__(self, group):
        super().__init__()
        self.group = group

    def forward(self, x):
        s = x.shape
        return F.softmax(x.reshape(*s[:-1], s[-1] // self.group, self.group), dim=-1).reshape(s)


class LoBSTrNet(nn.Module):
    """GRU(in->hidden) -> Linear(hidden->latent)+ReLU -> pose Linear(latent->48) | contact Linear(latent->4)
    with a softmax per foot. Output [pose 48 | contact 4]."""

    kind = "lobstr"

    def __init__(self, hidden=1024, latent=128, inputs=37):
        super().__init__()
        self.inputs, self.outputs = inputs, 52
        self.gru = nn.GRU(inputs, hidden, batch_first=True)
        self.latent = nn.Linear(hidden, latent)
        self.pose = nn.Linear(latent, 48)
        self.contact = nn.Linear(latent, 4)
        self.softmax = GroupSoftmax(2)

    def forward(self, x, h=None, logits=False):
        y, h = self.gru(x, h)
        lat = F.relu(self.latent(y))
        c = self.contact(lat)
        return torch.cat([self.pose(lat), c if logits else self.softmax(c)], -1), h


class N3PPredictor(nn.Module):
    """Neural3Points sub-predictor: Linear encoder, 3-layer GRU, Linear decoder (dropout in training)."""

    def __init__(self, inputs, hidden, outputs, layers=3, dropout_in=0.1, dropout_out=0.05, kind="n3p_signal"):
        super().__init__()
        self.kind, self.inputs, self.outputs = kind, inputs, outputs
        self.encoder = nn.Linear(inputs, hidden)
        self.gru = nn.GRU(hidden, hidden, num_layers=layers, batch_first=True)
        self.decoder = nn.Linear(hidden, outputs)
        self.drop_in, self.drop_out = nn.Dropout(dropout_in), nn.Dropout(dropout_out)

    def forward(self, x, h=None):
        y, h = self.gru(self.drop_in(self.encoder(x)), h)
        return self.decoder(self.drop_out(y)), h


_ACTS = {"identity": nn.Identity, "relu": nn.ReLU, "tanh": nn.Tanh, "sigmoid": nn.Sigmoid, "elu": nn.ELU}


class MLPPolicy(nn.Module):
    """MLP whose Linear layers are ``layers.<i>``; hidden_act after each hidden layer, out_act at the end.
    N3P policy: [in, 256, 256, out], relu/identity. QuestSim: [in, 400, 300, 200, out], tanh/tanh."""

    def __init__(self, sizes, hidden_act="relu", out_act="identity", kind="mlp"):
        super().__init__()
        self.kind, self.inputs, self.outputs = kind, sizes[0], sizes[-1]
        self.layers = nn.ModuleList(nn.Linear(a, b) for a, b in zip(sizes[:-1], sizes[1:]))
        self.hidden_act, self.out_act = _ACTS[hidden_act](), _ACTS[out_act]()

    def forward(self, x, h=None):
        for i, layer in enumerate(self.layers):
            x = layer(x)
            x = self.out_act(x) if i + 1 == len(self.layers) else self.hidden_act(x)
        return x, h


class GRUStack(nn.Module):
    """A bare torch.nn.GRU(num_layers=k) under the name ``gru`` (C++ Named<"gru", GRU<T,In,H,k>>)."""

    kind = "gru"

    def __init__(self, inputs, hidden, layers):
        super().__init__()
        self.inputs, self.outputs = inputs, hidden
        self.gru = nn.GRU(inputs, hidden, num_layers=layers, batch_first=True)

    def forward(self, x, h=None):
        return self.gru(x, h)


class LayerZoo(nn.Module):
    """Every stateless layer kind in one nn.Sequential (indexed names "0.weight", "2.weight", ...):
    Linear, ReLU, Linear without bias, Tanh, Linear, Sigmoid, Linear, ELU, Linear, softmax per pair."""

    kind = "sequential"

    def __init__(self):
        super().__init__()
        self.inputs, self.outputs = 13, 8
        self.net = nn.Sequential(nn.Linear(13, 29), nn.ReLU(), nn.Linear(29, 31, bias=False), nn.Tanh(),
                                 nn.Linear(31, 17), nn.Sigmoid(), nn.Linear(17, 19), nn.ELU(),
                                 nn.Linear(19, 8), GroupSoftmax(2))

    def forward(self, x, h=None):
        return self.net(x), h

    def state_dict_for_export(self):
        return self.net.state_dict()


def export_state_dict(module):
    """The state_dict under the names the C++ network binds."""
    if hasattr(module, "state_dict_for_export"):
        return module.state_dict_for_export()
    return module.state_dict()
