"""Writer and reader of the sparsebody weights format (version 1, see FORMAT.md)."""
import base64
import json

import numpy as np

from . import FORMAT, VERSION

KNOWN_KINDS = ("mlp", "gru", "sequential", "lobstr", "n3p_signal", "n3p_lower", "n3p_upper",
               "n3p_policy", "n3p_correction_policy", "questsim_policy")


def _as_numpy(t):
    if hasattr(t, "detach"):
        t = t.detach().cpu().numpy()
    return np.asarray(t)


def encode_tensor(t, dtype="float32", encoding="base64"):
    """One tensor as a JSON object: base64 little-endian (compact, fast to load) or a flat list."""
    a = _as_numpy(t)
    if not np.all(np.isfinite(a)):
        raise ValueError("non-finite value in tensor")
    if encoding == "list":
        return {"shape": list(a.shape), "data": a.astype(np.float64).ravel().tolist()}
    npdt = {"float32": "<f4", "float64": "<f8"}[dtype]
    raw = np.ascontiguousarray(a.astype(npdt)).tobytes()
    return {"shape": list(a.shape), "dtype": dtype, "data": base64.b64encode(raw).decode("ascii")}


def decode_tensor(obj):
    shape = tuple(obj["shape"])
    data = obj["data"]
    if isinstance(data, str):
        npdt = {"float32": "<f4", "float64": "<f8"}[obj.get("dtype", "float32")]
        return np.frombuffer(base64.b64decode(data), dtype=npdt).astype(np.float64).reshape(shape)
    return np.asarray(data, dtype=np.float64).reshape(shape)


def build_document(state_dict, kind, input_size, output_size, meta=None, normalization=None,
                   dtype="float32", encoding="base64"):
    """The weights document as a dict. `state_dict` maps PyTorch names to tensors."""
    if kind not in KNOWN_KINDS:
        raise ValueError(f"unknown model kind {kind!r} (known: {', '.join(KNOWN_KINDS)})")
    m = {"input_size": int(input_size), "output_size": int(output_size)}
    m.update(meta or {})
    doc = {"format": FORMAT, "version": VERSION, "kind": kind, "meta": m,
           "tensors": {k: encode_tensor(v, dtype, encoding) for k, v in state_dict.items()}}
    if normalization:
        doc["normalization"] = {k: encode_tensor(v, dtype, encoding) for k, v in normalization.items()}
    return doc


def write_weights(path, state_dict, kind, input_size, output_size, **kw):
    doc = build_document(state_dict, kind, input_size, output_size, **kw)
    with open(path, "w") as f:
        json.dump(doc, f, separators=(",", ":"))
    return doc


def read_weights(path):
    """Returns (doc, tensors, normalization) with tensors decoded to float64 numpy arrays."""
    with open(path) as f:
        doc = json.load(f)
    if doc.get("format") != FORMAT or doc.get("version") != VERSION:
        raise ValueError(f"{path}: not a {FORMAT} version {VERSION} file")
    tensors = {k: decode_tensor(v) for k, v in doc["tensors"].items()}
    norm = {k: decode_tensor(v) for k, v in doc.get("normalization", {}).items()}
    return doc, tensors, norm
