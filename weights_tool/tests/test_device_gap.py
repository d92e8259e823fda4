"""weights_tool.device_gap's bookkeeping (the figures themselves need the validation split: README,
"Off the training distribution")."""
import numpy as np

from weights_tool import device_gap, offdist


class FakeClip:
    """A clip of F frames whose 12 role joints sit at known places (floor 0)."""

    def __init__(self, F):
        self.frames = F
        self.roles = {k: i for i, k in enumerate(offdist.ROLES)}
        self.pw = np.arange(F * 12 * 3, dtype=float).reshape(F, 12, 3) / 100.0

    def floor(self):
        return 0.0


def test_held_prepends_the_first_frame():
    inp = {"time": np.array([0.5, 0.6, 0.7]), "position": np.arange(3 * 4 * 3.0).reshape(3, 4, 3),
           "orientation": np.zeros((3, 4, 4)), "valid": np.ones((3, 4), bool), "leg": 0.8}
    out = device_gap.held(inp, 2)
    assert out["position"].shape == (5, 4, 3)
    assert np.array_equal(out["position"][:3], np.repeat(inp["position"][:1], 3, 0))
    assert np.array_equal(out["position"][2:], inp["position"])
    assert np.allclose(out["time"], [0.5, 0.6, 0.7, 0.8, 0.9]) and out["leg"] == 0.8
    assert inp["position"].shape == (3, 4, 3)  # the input is not changed


def test_errors_align_rows_after_the_stand():
    c = FakeClip(4)
    P = np.concatenate([np.full((2, 12, 3), 9.0), c.pw + np.array([0.0, 0.03, 0.04])])  # 2 stand rows, then 5 cm off
    e = device_gap.errors(P, c, 2)
    assert e.shape == (4, 12) and np.allclose(e, 0.05)
    assert np.allclose(device_gap.errors(c.pw, c, 0), 0.0)
    assert device_gap.errors(np.zeros((3, 12, 3)), c, 0).shape == (3, 12)  # fewer rows: the frames they show
    assert device_gap.errors(np.zeros((9, 12, 3)), c, 2).shape == (4, 12)  # more: rows past the clip dropped
