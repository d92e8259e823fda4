"""BVH reader and forward kinematics (numpy).

Any channel count and order per joint; rotation channels compose in the listed order
(R = R_c1 @ R_c2 @ R_c3, the BVH convention); position channels of a non-root joint replace its
offset (as in the Bandai Namco data, whose 6-channel joints repeat their offsets).
"""
import numpy as np

from .rotations import AXES, axis_angle


class BVHError(ValueError):
    pass


class BVH:
    def __init__(self):
        self.names, self.parents, self.offsets, self.channels = [], [], [], []
        self.end_offsets = {}      # joint index -> End Site offset
        self.frame_time = 1.0 / 30
        self.motion = None         # [frames, total channels]

    @property
    def frames(self):
        return self.motion.shape[0]

    def index(self, name):
        return self.names.index(name)


def load(path):
    with open(path) as f:
        text = f.read()
    return parse(text, path)


def parse(text, source="<bvh>"):
    b = BVH()
    lines = text.splitlines()
    stack, i, pending_end = [], 0, False

    def err(msg):
        raise BVHError(f"{source}:{i + 1}: {msg}")

    while i < len(lines):
        tok = lines[i].split()
        if not tok or tok[0] == "HIERARCHY":
            i += 1
            continue
        if tok[0] in ("ROOT", "JOINT"):
            if len(tok) < 2:
                err("expected a joint name")
            b.names.append(tok[1])
            b.parents.append(stack[-1] if stack else -1)
            b.offsets.append(np.zeros(3))
            b.channels.append([])
            pending_end = False
        elif tok[0] == "End":
            pending_end = True
        elif tok[0] == "{":
            stack.append(-2 if pending_end else len(b.names) - 1)
        elif tok[0] == "}":
            if not stack:
                err("unbalanced '}'")
            stack.pop()
            pending_end = False
        elif tok[0] == "OFFSET":
            if len(tok) != 4:
                err("expected OFFSET x y z")
            v = np.array([float(t) for t in tok[1:4]])
            if stack and stack[-1] == -2:
                b.end_offsets[[j for j in stack if j >= 0][-1]] = v
            else:
                b.offsets[-1] = v
        elif tok[0] == "CHANNELS":
            n = int(tok[1])
            if len(tok) != 2 + n:
                err(f"expected {n} channel names")
            b.channels[-1] = tok[2:]
        elif tok[0] == "MOTION":
            break
        else:
            err(f"unexpected token '{tok[0]}'")
        i += 1
    i += 1
    nf = int(lines[i].split(":")[1])
    i += 1
    b.frame_time = float(lines[i].split(":")[1])
    nch = sum(len(c) for c in b.channels)
    rows = [l for l in lines[i + 1:] if l.strip()]
    if len(rows) < nf:
        raise BVHError(f"{source}: expected {nf} frames, found {len(rows)}")
    first = i + 2  # line number of the first frame
    vals = []
    for k, r in enumerate(rows[:nf]):
        v = r.split()
        if len(v) != nch:
            raise BVHError(f"{source}: frame {k}: expected {nch} values per frame, found {len(v)}")
        vals.append([float(x) for x in v])
    del first
    b.motion = np.array(vals, dtype=np.float64).reshape(nf, nch)
    return b


def local_transforms(b):
    """Local rotations [F, J, 3, 3] and translations [F, J, 3] per joint."""
    F, J = b.frames, len(b.names)
    R = np.tile(np.eye(3), (F, J, 1, 1))
    t = np.tile(np.stack(b.offsets), (F, 1, 1))
    c = 0
    for j, chans in enumerate(b.channels):
        for name in chans:
            v = b.motion[:, c]
            c += 1
            axis, kind = name[0].upper(), name[1:].lower()
            if kind == "position":
                t[:, j, "XYZ".index(axis)] = v
            elif kind == "rotation":
                R[:, j] = R[:, j] @ axis_angle(AXES[axis], v)
    return R, t


def fk(parents, R_local, t_local):
    """World rotations and positions [F, J, 3, 3], [F, J, 3] (joints ordered parents first)."""
    Rw, pw = np.empty_like(R_local), np.empty_like(t_local)
    for j, p in enumerate(parents):
        if p < 0:
            Rw[:, j], pw[:, j] = R_local[:, j], t_local[:, j]
        else:
            Rw[:, j] = Rw[:, p] @ R_local[:, j]
            pw[:, j] = pw[:, p] + np.einsum("fij,fj->fi", Rw[:, p], t_local[:, j])
    return Rw, pw
