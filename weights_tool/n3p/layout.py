"""Layouts of the Neural3Points quantities and the heading frame h (paper §4).

Heading frame h = (p_x, p_z, theta_y): a frame on the ground at (p_x, 0, p_z), Y up, rotated by theta_y
about Y so that its Z axis is the character's facing direction. R_y(theta) maps (0, 0, 1) to
(sin theta, 0, cos theta). Ground truth h: hips position on the ground, theta from the pelvis frame's
forward (Z) axis (weights_tool/lobstr/skeleton.py).
  inv(h) (x) p      = R_y(-theta) (p - (p_x, 0, p_z))          (a point into the frame)
  h1 (x) dh         = (p1 + R_y(theta1) (dx, 0, dz), theta1 + dtheta), theta wrapped to (-pi, pi]
  delta(h0, h1)     = inv(h0) (x) h1

Vectors (velocities, momenta, the two columns of a 6D rotation) transform with R_y only.

Layouts (all in a heading frame; the 6D of a rotation is columns [2, 1], as weights_tool/lobstr):
  o     trackers X in {H, L, R}: [p_H p_L p_R (9) | q6_H q6_L q6_R (18)]                       27
  z     [p_up (3) | v_up (3) | L_up (3) | dh = (dx, dz, dtheta) (3)]                            12
  g_lo  [p_j (27) | v_j (27) | q6_j (54) for j in J_lo | c_L c_R (2) | z (12)]                  122
  g_up  [p_j (36) | v_j (36) | q6_j (72) for j in J_up]                                          144
Networks (paper Eq. (2)):
  G_sig: inv(h^{t-1}) (x) o^t (27)                    -> z~^t (12)
  G_lo : [z~^t (12) | g_lo^{t-1} (122)]  (134)        -> [g_lo^t (122) | z*^{t+1} (12)]   (134)
  G_up : [inv(h^t) (x) o^t (27) | g_up^{t-1} (144)]   -> [g_up^t (144) | o*^{t+1} (27)]   (171)
"""
import math

import torch

from ..lobstr.standard import STANDARD

NAMES = STANDARD["names"]
PARENTS = STANDARD["parents"]
J_LO = ["Hips", "UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"]
J_UP = ["Spine", "Chest", "Neck", "Head", "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L",
        "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R"]
TRACKERS = ["Head", "Hand_L", "Hand_R"]
I_LO = [NAMES.index(n) for n in J_LO]
I_UP = [NAMES.index(n) for n in J_UP]
I_TR = [NAMES.index(n) for n in TRACKERS]

N_O, N_Z = 27, 12
N_GLO = 12 * len(J_LO) + 2 + N_Z        # 122
N_GUP = 12 * len(J_UP)                  # 144
SIG_IN, SIG_OUT = N_O, N_Z
LO_IN, LO_OUT = N_Z + N_GLO, N_GLO + N_Z
UP_IN, UP_OUT = N_O + N_GUP, N_GUP + N_O
Z_IN_GLO = 12 * len(J_LO) + 2           # offset of z inside g_lo
DH_IN_GLO = Z_IN_GLO + 9                # offset of dh inside g_lo
CONTACT_IN_GLO = 12 * len(J_LO)
FPS = 30.0


def wrap(a):
    return torch.atan2(torch.sin(a), torch.cos(a))


def rot_inv(h, v):
    """R_y(-theta) v for h [..., 3], v [..., k, 3] (k vectors per frame)."""
    c, s = torch.cos(h[..., 2])[..., None], torch.sin(h[..., 2])[..., None]
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return torch.stack([c * x - s * z, y, s * x + c * z], -1)


def rot(h, v):
    """R_y(theta) v."""
    c, s = torch.cos(h[..., 2])[..., None], torch.sin(h[..., 2])[..., None]
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return torch.stack([c * x + s * z, y, -s * x + c * z], -1)


def point_inv(h, p):
    """inv(h) (x) p for points p [..., k, 3]."""
    o = torch.stack([h[..., 0], torch.zeros_like(h[..., 0]), h[..., 1]], -1)[..., None, :]
    return rot_inv(h, p - o)


def point(h, p):
    o = torch.stack([h[..., 0], torch.zeros_like(h[..., 0]), h[..., 1]], -1)[..., None, :]
    return rot(h, p) + o


def compose(h, dh):
    """h (x) dh."""
    d = torch.stack([dh[..., 0], torch.zeros_like(dh[..., 0]), dh[..., 1]], -1)[..., None, :]
    w = rot(h, d)[..., 0, :]
    return torch.stack([h[..., 0] + w[..., 0], h[..., 1] + w[..., 2], wrap(h[..., 2] + dh[..., 2])], -1)


def delta(h0, h1):
    """inv(h0) (x) h1."""
    d = torch.stack([h1[..., 0] - h0[..., 0], torch.zeros_like(h0[..., 0]), h1[..., 1] - h0[..., 1]], -1)[..., None, :]
    r = rot_inv(h0, d)[..., 0, :]
    return torch.stack([r[..., 0], r[..., 2], wrap(h1[..., 2] - h0[..., 2])], -1)


def rot6_inv(h, q6):
    """6D rotations [..., k, 6] (two world columns) into the frame."""
    k = q6.shape[-2]
    return rot_inv(h, q6.reshape(*q6.shape[:-2], 2 * k, 3)).reshape(q6.shape)


def rot6(h, q6):
    k = q6.shape[-2]
    return rot(h, q6.reshape(*q6.shape[:-2], 2 * k, 3)).reshape(q6.shape)


def tracker_input(h, P, Q6):
    """o in frame h: P [..., 3, 3] world positions, Q6 [..., 3, 6] world 6D -> [..., 27]."""
    p = point_inv(h, P).flatten(-2)
    q = rot6_inv(h, Q6).flatten(-2)
    return torch.cat([p, q], -1)


def tracker_world(h, o):
    """Inverse of tracker_input: o [..., 27] in frame h -> (P [..., 3, 3], Q6 [..., 3, 6]) world."""
    P = point(h, o[..., :9].reshape(*o.shape[:-1], 3, 3))
    Q6 = rot6(h, o[..., 9:27].reshape(*o.shape[:-1], 3, 6))
    return P, Q6


def joint_state(h, P, V, Q6):
    """[p (3k) | v (3k) | q6 (6k)] in frame h from world P, V [..., k, 3], Q6 [..., k, 6]."""
    return torch.cat([point_inv(h, P).flatten(-2), rot_inv(h, V).flatten(-2), rot6_inv(h, Q6).flatten(-2)], -1)


def z_state(h, h_prev, C, Cv, L):
    """z in frame h: centroid C, its velocity Cv, angular momentum L (world [..., 3]), dh = delta(h_prev, h)."""
    return torch.cat([point_inv(h, C[..., None, :])[..., 0, :], rot_inv(h, Cv[..., None, :])[..., 0, :],
                      rot_inv(h, L[..., None, :])[..., 0, :], delta(h_prev, h)], -1)


def rot6_to_matrix(d):
    """6D (columns [2, 1]) -> rotation matrix, as weights_tool/lobstr: z = a/|a|, x = b x z /|.|, y = z x x."""
    a, b = d[..., 0:3], d[..., 3:6]
    z = a / a.norm(dim=-1, keepdim=True).clamp(min=1e-8)
    x = torch.cross(b, z, dim=-1)
    x = x / x.norm(dim=-1, keepdim=True).clamp(min=1e-8)
    y = torch.cross(z, x, dim=-1)
    return torch.stack([x, y, z], -1)


def offsets(dtype=torch.float32):
    return torch.tensor(STANDARD["offsets"], dtype=dtype)


def fk_residual(state, joints, dtype=torch.float32):
    """L_FK: for every joint of the set whose parent is in the set, p_j - (p_parent + R_parent off_j)
    from the predicted positions and orientations of a state [..., 12k (+ more)]. Returns [..., m, 3]."""
    k = len(joints)
    P = state[..., :3 * k].reshape(*state.shape[:-1], k, 3)
    R = rot6_to_matrix(state[..., 6 * k:12 * k].reshape(*state.shape[:-1], k, 6))
    off = offsets(state.dtype)
    res = []
    for i, n in enumerate(joints):
        par = PARENTS[NAMES.index(n)]
        if par >= 0 and NAMES[par] in joints:
            pi = joints.index(NAMES[par])
            o = off[NAMES.index(n)]
            res.append(P[..., i, :] - P[..., pi, :] - torch.einsum("...ij,j->...i", R[..., pi, :, :], o))
    return torch.stack(res, -2)


def heading_from_forward(pos, fwd):
    """h from a ground position and a forward vector (numpy-free helper for torch tensors [..., 3])."""
    return torch.stack([pos[..., 0], pos[..., 2], torch.atan2(fwd[..., 0], fwd[..., 2])], -1)


PI = math.pi
