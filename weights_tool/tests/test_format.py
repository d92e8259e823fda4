import base64
import json

import numpy as np
import pytest
import torch

from weights_tool.format import build_document, decode_tensor, encode_tensor, read_weights, write_weights


def test_base64_round_trip_is_exact_in_float32_and_float64():
    a = np.random.default_rng(0).normal(size=(5, 7)).astype(np.float32)
    for dtype in ("float32", "float64"):
        t = encode_tensor(a, dtype)
        assert t["shape"] == [5, 7] and t["dtype"] == dtype
        np.testing.assert_array_equal(decode_tensor(t), a.astype(np.float64))


def test_base64_is_little_endian_ieee():
    t = encode_tensor(np.array([1.0, -2.5], dtype=np.float32))
    assert base64.b64decode(t["data"]) == np.array([1.0, -2.5], dtype="<f4").tobytes()


def test_list_encoding_round_trip():
    a = np.arange(6, dtype=np.float64).reshape(2, 3) / 7
    t = encode_tensor(a, encoding="list")
    assert t["data"] == a.ravel().tolist()
    np.testing.assert_array_equal(decode_tensor(t), a)


def test_non_finite_values_are_refused():
    with pytest.raises(ValueError, match="non-finite"):
        encode_tensor(np.array([1.0, np.nan]))


def test_unknown_kind_is_refused():
    with pytest.raises(ValueError, match="unknown model kind"):
        build_document({}, "transformer", 1, 1)


def test_write_and_read_back_a_module(tmp_path):
    lin = torch.nn.Linear(3, 2)
    p = tmp_path / "m.json"
    write_weights(p, lin.state_dict(), "mlp", 3, 2, meta={"frame_rate": 30},
                  normalization={"input_mean": np.zeros(3), "input_std": np.ones(3)})
    doc, tensors, norm = read_weights(p)
    assert doc["format"] == "sparsebody-weights" and doc["version"] == 1 and doc["kind"] == "mlp"
    assert doc["meta"] == {"input_size": 3, "output_size": 2, "frame_rate": 30}
    np.testing.assert_array_equal(tensors["weight"], lin.weight.detach().numpy().astype(np.float64))
    assert set(norm) == {"input_mean", "input_std"}
    json.loads(p.read_text())  # plain JSON


def test_read_refuses_other_formats(tmp_path):
    p = tmp_path / "x.json"
    p.write_text(json.dumps({"format": "sparsebody-weights", "version": 2}))
    with pytest.raises(ValueError, match="version 1"):
        read_weights(p)
