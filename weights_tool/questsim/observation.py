"""QuestSim observation in torch (float64), written independently of the C++ builder: world-frame
forward kinematics of the model JSON (dynamics/model_json.hpp schema) from (q, v), then the floor
heading frame S and the blocks of layout.py.

State conventions (dynamics/joint.hpp): free root q = (p, quaternion w x y z), v = (body angular,
body linear velocity); spherical q = quaternion, v = child-frame angular velocity; revolute q = angle,
v = rate. A body's world rotation is R_parent R_T R_J, its origin p_parent + R_parent pos.
"""
import math

import torch

from .layout import layout

FEET = (("Foot_L", "Toes_L"), ("Foot_R", "Toes_R"))


def quat_matrix(q):
    """(w, x, y, z) -> rotation matrix (normalised first)."""
    q = q / torch.linalg.norm(q)
    w, x, y, z = q
    return torch.stack([
        torch.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)]),
        torch.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)]),
        torch.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]),
    ])


def axis_angle_matrix(axis, angle):
    """Rodrigues' formula."""
    a = axis / torch.linalg.norm(axis)
    K = torch.tensor([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]], dtype=torch.float64)
    return torch.eye(3, dtype=torch.float64) + torch.sin(angle) * K + (1 - torch.cos(angle)) * (K @ K)


def rotation_vector(q):
    """Rotation vector of a quaternion (w, x, y, z), w >= 0 (the shorter rotation)."""
    q = q / torch.linalg.norm(q)
    if q[0] < 0:
        q = -q
    v = q[1:]
    s = torch.linalg.norm(v)
    if s < 1e-8:
        return 2 * v / q[0]
    return v * (2 * torch.atan2(s, q[0]) / s)


def _nq(joint):
    return {"free": 7, "spherical": 4, "revolute": 1, "fixed": 0}[joint]


def _nv(joint):
    return {"free": 6, "spherical": 3, "revolute": 1, "fixed": 0}[joint]


def forward_kinematics(model, q, v):
    """World R (nb,3,3), p (nb,3), angular velocity w (nb,3), origin linear velocity vl (nb,3)."""
    t = lambda a: torch.as_tensor(a, dtype=torch.float64)
    bodies = model["bodies"]
    index = {b["name"]: i for i, b in enumerate(bodies)}
    R, p, w, vl, qi, vi = [], [], [], [], 0, 0
    for b in bodies:
        j = b["joint"]
        if j == "free":
            Ri = quat_matrix(q[qi + 3:qi + 7])
            pi = q[qi:qi + 3]
            wi = Ri @ v[vi:vi + 3]
            vli = Ri @ v[vi + 3:vi + 6]
        else:
            par = index[b["parent"]]
            RT = quat_matrix(t(b.get("quat", [1, 0, 0, 0])))
            if j == "spherical":
                RJ, wJ = quat_matrix(q[qi:qi + 4]), v[vi:vi + 3]
            elif j == "revolute":
                ax = t(b["axis"])
                RJ, wJ = axis_angle_matrix(ax, q[qi]), ax / torch.linalg.norm(ax) * v[vi]
            else:
                RJ, wJ = torch.eye(3, dtype=torch.float64), torch.zeros(3, dtype=torch.float64)
            Ri = R[par] @ RT @ RJ
            pi = p[par] + R[par] @ t(b["pos"])
            wi = w[par] + Ri @ wJ
            vli = vl[par] + torch.linalg.cross(w[par], pi - p[par])
        R.append(Ri); p.append(pi); w.append(wi); vl.append(vli)
        qi += _nq(j)
        vi += _nv(j)
    return torch.stack(R), torch.stack(p), torch.stack(w), torch.stack(vl)


def floor_frame(R0, p0):
    """R_S = R_y(theta), theta = atan2(f_x, f_z) of the root's forward axis f = R0 e_z; origin below the root."""
    f = R0[:, 2]
    theta = math.atan2(float(f[0]), float(f[2])) if abs(float(f[0])) + abs(float(f[2])) > 1e-12 else 0.0
    c, s = math.cos(theta), math.sin(theta)
    Rs = torch.tensor([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]], dtype=torch.float64)
    o = torch.stack([p0[0], torch.zeros((), dtype=torch.float64), p0[2]])
    return Rs, o


def observation(model, q, v, contacts, user, height, future=6):
    """The observation vector (float64). contacts: [(body, fx, fy, fz)] world forces of active contacts;
    user: future + 1 frames of 3 devices (headset, left, right), each [px, py, pz, qw, qx, qy, qz] world."""
    t = lambda a: torch.as_tensor(a, dtype=torch.float64)
    q, v = t(q), t(v)
    bodies = model["bodies"]
    nb = len(bodies)
    nj = sum(_nv(b["joint"]) for b in bodies) - 6
    L = layout(nb, nj, future)
    out = torch.zeros(L["size"], dtype=torch.float64)
    R, p, w, vl = forward_kinematics(model, q, v)
    Rs, o = floor_frame(R[0], p[0])
    RsT = Rs.T
    # joints
    qi, vi, k = 7, 6, 0
    for b in bodies[1:]:
        j = b["joint"]
        if j == "spherical":
            out[L["q"] + k:L["q"] + k + 3] = rotation_vector(q[qi:qi + 4])
            out[L["qd"] + k:L["qd"] + k + 3] = v[vi:vi + 3]
        elif j == "revolute":
            out[L["q"] + k] = q[qi]
            out[L["qd"] + k] = v[vi]
        qi += _nq(j)
        vi += _nv(j)
        k += _nv(j)
    # links
    for i in range(nb):
        Rl = RsT @ R[i]
        out[L["x"] + 3 * i:L["x"] + 3 * i + 3] = RsT @ (p[i] - o)
        out[L["R"] + 6 * i:L["R"] + 6 * i + 6] = torch.cat([Rl[:, 0], Rl[:, 1]])
        out[L["xd"] + 3 * i:L["xd"] + 3 * i + 3] = RsT @ vl[i]
        out[L["w"] + 3 * i:L["w"] + 3 * i + 3] = RsT @ w[i]
    # feet
    names = [b["name"] for b in bodies]
    for side, feet in enumerate(FEET):
        ids = {names.index(n) for n in feet if n in names}
        f = torch.zeros(3, dtype=torch.float64)
        for c in contacts:
            if int(c[0]) in ids:
                f = f + t(c[1:4])
        out[L["f"] + 3 * side:L["f"] + 3 * side + 3] = RsT @ f
    # user frames t .. t+future
    for fr in range(future + 1):
        for dev in range(3):
            e = user[fr][dev]
            Rd = RsT @ quat_matrix(t(e[3:7]))
            base = L["user"] + 27 * fr + 9 * dev
            out[base:base + 3] = RsT @ (t(e[0:3]) - o)
            out[base + 3:base + 9] = torch.cat([Rd[:, 0], Rd[:, 1]])
    out[L["height"]] = height
    return out
