"""The reference modules implement the equations the C++ layers implement, under the C++ names."""
import numpy as np
import torch

from weights_tool import nets


def gru_step_numpy(sd, k, x, h):
    """PyTorch's documented GRU equations (gate order r, z, n; b_hn inside the reset product)."""
    H = h.shape[0]
    W_ih, W_hh = sd[f"gru.weight_ih_l{k}"], sd[f"gru.weight_hh_l{k}"]
    b_ih, b_hh = sd[f"gru.bias_ih_l{k}"], sd[f"gru.bias_hh_l{k}"]
    gi, gh = W_ih @ x + b_ih, W_hh @ h + b_hh
    sig = lambda v: 1 / (1 + np.exp(-v))
    r, z = sig(gi[:H] + gh[:H]), sig(gi[H:2 * H] + gh[H:2 * H])
    n = np.tanh(gi[2 * H:] + r * gh[2 * H:])
    return (1 - z) * n + z * h


def test_gru_stack_matches_the_equations():
    torch.manual_seed(0)
    m = nets.GRUStack(5, 7, 2).double().eval()
    sd = {k: v.numpy() for k, v in m.state_dict().items()}
    x = np.random.default_rng(1).normal(size=(20, 5))
    with torch.no_grad():
        y, _ = m(torch.from_numpy(x)[None])
    h = [np.zeros(7), np.zeros(7)]
    for t in range(20):
        h[0] = gru_step_numpy(sd, 0, x[t], h[0])
        h[1] = gru_step_numpy(sd, 1, h[0], h[1])
        np.testing.assert_allclose(y[0, t].numpy(), h[1], atol=1e-12)


def test_lobstr_names_shapes_and_contact_softmax():
    m = nets.LoBSTrNet(hidden=16, latent=8).eval()
    shapes = {k: tuple(v.shape) for k, v in m.state_dict().items()}
    assert shapes == {"gru.weight_ih_l0": (48, 37), "gru.weight_hh_l0": (48, 16), "gru.bias_ih_l0": (48,),
                      "gru.bias_hh_l0": (48,), "latent.weight": (8, 16), "latent.bias": (8,),
                      "pose.weight": (48, 8), "pose.bias": (48,), "contact.weight": (4, 8), "contact.bias": (4,)}
    with torch.no_grad():
        y, h = m(torch.randn(2, 5, 37))
        logits, _ = m(torch.randn(1, 3, 37), logits=True)
    assert y.shape == (2, 5, 52) and h.shape == (1, 2, 16)
    np.testing.assert_allclose(y[..., 48:50].sum(-1).numpy(), 1, atol=1e-6)
    np.testing.assert_allclose(y[..., 50:52].sum(-1).numpy(), 1, atol=1e-6)
    assert not torch.allclose(logits[..., 48:50].sum(-1), torch.ones(1))


def test_n3p_predictor_and_policies_names():
    p = nets.N3PPredictor(45, 64, 12)
    assert sorted(p.state_dict())[:2] == ["decoder.bias", "decoder.weight"]
    assert "gru.weight_hh_l2" in p.state_dict() and "gru.weight_hh_l3" not in p.state_dict()
    q = nets.MLPPolicy([475, 400, 300, 200, 33], "tanh", "tanh")
    assert [tuple(q.state_dict()[f"layers.{i}.weight"].shape) for i in range(4)] == \
        [(400, 475), (300, 400), (200, 300), (33, 200)]
    with torch.no_grad():
        y, _ = q(torch.randn(1, 475) * 10)
    assert y.abs().max() <= 1  # tanh output, scaled to +/-200 Nm by the caller


def test_dropout_is_inactive_in_eval():
    torch.manual_seed(0)
    p = nets.N3PPredictor(4, 8, 3).eval()
    x = torch.randn(1, 6, 4)
    with torch.no_grad():
        assert torch.equal(p(x)[0], p(x)[0])


def test_layer_zoo_uses_nn_sequential_indices():
    names = list(nets.export_state_dict(nets.LayerZoo()))
    assert names == ["0.weight", "0.bias", "2.weight", "4.weight", "4.bias", "6.weight", "6.bias",
                     "8.weight", "8.bias"]
