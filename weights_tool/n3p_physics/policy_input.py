"""Neural3Points control-policy input s = {x_t, g_t+1, g_t+2, g_t+3} in the reference heading frame
(paper §5). Twin of include/sparsebody/control/n3p_policy_input.hpp (same layout, see there):
per joint of the standard skeleton, blocks [p (21x3) | v (21x3) | q6 (21x6)] = 252 values; x_t from
the simulated character (world positions, velocities, rotations), g_t+k from predicted states
(g_lo, g_up in their own heading h_k) re-expressed in h_ref. s = 1008 values. Float64 numpy."""
import numpy as np

N_LO, N_UP = 9, 12
J = N_LO + N_UP
BLOCK = 12 * J
POLICY_IN = 4 * BLOCK
POLICY_OUT = 6 * (J - 1)


def ry(theta):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def to_local_point(h, p):
    return ry(h[2]).T @ (np.asarray(p) - np.array([h[0], 0.0, h[1]]))


def to_world_point(h, p):
    return ry(h[2]) @ np.asarray(p) + np.array([h[0], 0.0, h[1]])


def _put(out, h_ref, j, p, v, fwd, up):
    r = ry(h_ref[2]).T
    out[3 * j:3 * j + 3] = to_local_point(h_ref, p)
    out[3 * J + 3 * j:3 * J + 3 * j + 3] = r @ v
    out[6 * J + 6 * j:6 * J + 6 * j + 3] = r @ fwd
    out[6 * J + 6 * j + 3:6 * J + 6 * j + 6] = r @ up


def character_block(h_ref, p, v, R):
    """x_t: p, v (J, 3) world; R (J, 3, 3) world rotations."""
    out = np.zeros(BLOCK)
    for j in range(J):
        _put(out, h_ref, j, p[j], v[j], R[j][:, 2], R[j][:, 1])
    return out


def predicted_block(h_ref, h_k, g_lo, g_up, lower, upper):
    """g_t+k from g_lo (122), g_up (144) in heading h_k; lower/upper: skeleton indices of J_lo/J_up."""
    out = np.zeros(BLOCK)
    rk = ry(h_k[2])
    for g, K, idx in ((np.asarray(g_lo), N_LO, lower), (np.asarray(g_up), N_UP, upper)):
        for i, j in enumerate(idx):
            p = g[3 * i:3 * i + 3]
            v = g[3 * K + 3 * i:3 * K + 3 * i + 3]
            q = g[6 * K + 6 * i:6 * K + 6 * i + 6]
            _put(out, h_ref, j, to_world_point(h_k, p), rk @ v, rk @ q[:3], rk @ q[3:])
    return out


def policy_input(h_ref, p, v, R, future, lower, upper):
    """future: three (h_k, g_lo, g_up) for g_t+1, g_t+2, g_t+3."""
    return np.concatenate([character_block(h_ref, p, v, R)] +
                          [predicted_block(h_ref, h, glo, gup, lower, upper) for h, glo, gup in future])
