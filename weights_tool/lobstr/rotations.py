"""Rotation helpers on 3x3 matrices (column vectors: v_world = R @ v_local), batched over leading axes.

6D layout (stored in the weights meta as "rot6d"): the rotated Z (forward) axis then the rotated Y
(up) axis, i.e. columns [2, 1] of R, following the paper's §3 "6-DoF with forward (Z-axis) and up
(Y-axis) vectors". Reconstruction: z = a/|a|, x = normalize(b x z), y = z x x.
"""
import numpy as np


def axis_angle(axis, deg):
    """Rotation matrix about a unit axis (3,) by deg degrees (scalar or array)."""
    a = np.deg2rad(np.asarray(deg, dtype=np.float64))
    x, y, z = axis
    c, s = np.cos(a), np.sin(a)
    C = 1 - c
    R = np.empty(a.shape + (3, 3))
    R[..., 0, 0] = c + x * x * C; R[..., 0, 1] = x * y * C - z * s; R[..., 0, 2] = x * z * C + y * s
    R[..., 1, 0] = y * x * C + z * s; R[..., 1, 1] = c + y * y * C; R[..., 1, 2] = y * z * C - x * s
    R[..., 2, 0] = z * x * C - y * s; R[..., 2, 1] = z * y * C + x * s; R[..., 2, 2] = c + z * z * C
    return R


AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def rodrigues(vec):
    """Rotation matrices from rotation vectors [..., 3] (radians)."""
    vec = np.asarray(vec, dtype=np.float64)
    th = np.linalg.norm(vec, axis=-1, keepdims=True)
    k = vec / np.maximum(th, 1e-12)
    K = np.zeros(vec.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2] = -k[..., 2], k[..., 1]
    K[..., 1, 0], K[..., 1, 2] = k[..., 2], -k[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -k[..., 1], k[..., 0]
    th = th[..., None]
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * (K @ K)


def to6d(R):
    """[..., 3, 3] -> [..., 6] = [R[:, 2], R[:, 1]] (forward, up)."""
    return np.concatenate([R[..., :, 2], R[..., :, 1]], axis=-1)


def from6d(d):
    """[..., 6] -> [..., 3, 3] (Gram-Schmidt, forward axis kept exactly)."""
    a, b = d[..., 0:3], d[..., 3:6]
    z = a / np.linalg.norm(a, axis=-1, keepdims=True)
    x = np.cross(b, z)
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)


def yaw_frame(forward, fallback=None):
    """Rotation about +Y whose Z axis is the ground projection of `forward` [..., 3].
    Where the projection is shorter than 1e-3 the previous frame's yaw is held (time axis -2..)."""
    f = np.array(forward, dtype=np.float64)
    f[..., 1] = 0.0
    n = np.linalg.norm(f, axis=-1)
    out = np.empty(f.shape[:-1] + (3, 3))
    z = f / np.maximum(n, 1e-12)[..., None]
    x = np.stack([z[..., 2], np.zeros_like(n), -z[..., 0]], axis=-1)  # x = y cross z
    out[..., :, 0], out[..., :, 1], out[..., :, 2] = x, 0.0, z
    out[..., 1, 1] = 1.0
    bad = n < 1e-3
    if np.any(bad):
        flat_o, flat_b = out.reshape(-1, 3, 3), bad.reshape(-1)
        for i in np.nonzero(flat_b)[0]:
            flat_o[i] = flat_o[i - 1] if i > 0 else (np.eye(3) if fallback is None else fallback)
    return out


def angle_between(Ra, Rb):
    """Geodesic angle (degrees) between rotation matrices."""
    c = (np.einsum("...ij,...ij->...", Ra, Rb) - 1.0) / 2.0
    return np.rad2deg(np.arccos(np.clip(c, -1.0, 1.0)))


def random_rotations(rng, n, max_deg):
    """n random rotations with uniform random axis and angle uniform in [0, max_deg]."""
    ax = rng.normal(size=(n, 3))
    ax /= np.linalg.norm(ax, axis=-1, keepdims=True)
    ang = np.deg2rad(rng.uniform(0.0, max_deg, size=(n, 1)))
    return rodrigues(ax * ang)


def matrix_to_quat(R):
    """[..., 3, 3] -> quaternions [..., 4] stored (x, y, z, w), w >= 0."""
    R = np.asarray(R, dtype=np.float64)
    w = np.sqrt(np.maximum(0.0, 1.0 + R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2])) / 2
    x = np.sqrt(np.maximum(0.0, 1.0 + R[..., 0, 0] - R[..., 1, 1] - R[..., 2, 2])) / 2
    y = np.sqrt(np.maximum(0.0, 1.0 - R[..., 0, 0] + R[..., 1, 1] - R[..., 2, 2])) / 2
    z = np.sqrt(np.maximum(0.0, 1.0 - R[..., 0, 0] - R[..., 1, 1] + R[..., 2, 2])) / 2
    x = np.copysign(x, R[..., 2, 1] - R[..., 1, 2])
    y = np.copysign(y, R[..., 0, 2] - R[..., 2, 0])
    z = np.copysign(z, R[..., 1, 0] - R[..., 0, 1])
    q = np.stack([x, y, z, w], axis=-1)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def quat_to_matrix(q):
    """Quaternions [..., 4] stored (x, y, z, w) (normalised first) -> [..., 3, 3]."""
    q = np.asarray(q, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1 - 2 * (y * y + z * z); R[..., 0, 1] = 2 * (x * y - z * w); R[..., 0, 2] = 2 * (x * z + y * w)
    R[..., 1, 0] = 2 * (x * y + z * w); R[..., 1, 1] = 1 - 2 * (x * x + z * z); R[..., 1, 2] = 2 * (y * z - x * w)
    R[..., 2, 0] = 2 * (x * z - y * w); R[..., 2, 1] = 2 * (y * z + x * w); R[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return R
