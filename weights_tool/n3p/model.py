"""The three sub-predictors with their normalisation, ground-truth features, and the Eq. (2) rollout.

The rollout is batched and generic over the geometry dtype: training runs it in float32; the C++
parity golden runs the geometry (heading frame, transforms) in float64 and the networks in float32,
as the C++ predictor does.
"""
import torch
from torch import nn

from ..nets import N3PPredictor
from . import layout as L

SIZES = {"sig": (L.SIG_IN, 64, L.SIG_OUT, "n3p_signal"),
         "lo": (L.LO_IN, 128, L.LO_OUT, "n3p_lower"),
         "up": (L.UP_IN, 128, L.UP_OUT, "n3p_upper")}


class Sub(nn.Module):
    """A sub-predictor G with input/output normalisation: y = G((x - mu_x) / sigma_x) * sigma_y + mu_y
    (the weights file's normalization section; the C++ network applies it inside step())."""

    def __init__(self, name, hidden=None, dropout=(0.1, 0.05)):
        super().__init__()
        i, h, o, kind = SIZES[name]
        h = hidden or h
        self.name, self.kind, self.hidden = name, kind, h
        self.net = N3PPredictor(i, h, o, dropout_in=dropout[0], dropout_out=dropout[1], kind=kind)
        for k, n in (("in_mean", i), ("out_mean", o)):
            self.register_buffer(k, torch.zeros(n))
        for k, n in (("in_std", i), ("out_std", o)):
            self.register_buffer(k, torch.ones(n))

    def forward(self, x, h=None):
        """x [B, T, in] raw -> (y raw, y normalised, hidden)."""
        dt = x.dtype
        yn, h = self.net(((x.float() - self.in_mean) / self.in_std), h)
        return (yn * self.out_std + self.out_mean).to(dt), yn, h

    def normalization(self):
        return {k: getattr(self, k).detach().clone() for k in ("in_mean", "in_std", "out_mean", "out_std")}


def targets(A, H):
    """Ground-truth features for frames 1..n-2 of world arrays A (dict of [B, n, ...]) in headings H
    [B, n, 3]. Index i of each result is frame i + 1."""
    s, p, n = slice(1, -1), slice(0, -2), slice(2, None)
    Hs, Hp, Hn = H[:, s], H[:, p], H[:, n]
    z = L.z_state(Hs, Hp, A["C"][:, s], A["Cv"][:, s], A["L"][:, s])
    zn = L.z_state(Hn, Hs, A["C"][:, n], A["Cv"][:, n], A["L"][:, n])
    lo = L.joint_state(Hs, A["P"][:, s][:, :, L.I_LO], A["V"][:, s][:, :, L.I_LO], A["Q6"][:, s][:, :, L.I_LO])
    up = L.joint_state(Hs, A["P"][:, s][:, :, L.I_UP], A["V"][:, s][:, :, L.I_UP], A["Q6"][:, s][:, :, L.I_UP])
    return dict(
        sig_in=L.tracker_input(Hp, A["TP"][:, s], A["TQ6"][:, s]),
        z=z, zn=zn,
        glo=torch.cat([lo, A["CT"][:, s], z], -1),
        gup=up,
        up_in=L.tracker_input(Hs, A["TP"][:, s], A["TQ6"][:, s]),
        onext=L.tracker_input(Hs, A["TP"][:, n], A["TQ6"][:, n]))


def initial_heading(TP0, TQ60, o0):
    """h^0 at start-up from the head tracker: theta from its forward (Z) axis, placed so that the default
    pose's head (o^0's p_H, in the frame) lies under the tracked head."""
    th = torch.atan2(TQ60[..., 0, 0], TQ60[..., 0, 2])
    h = torch.stack([torch.zeros_like(th), torch.zeros_like(th), th], -1)
    ph = L.rot(h, o0[..., None, 0:3])[..., 0, :]
    return torch.stack([TP0[..., 0, 0] - ph[..., 0], TP0[..., 0, 2] - ph[..., 2], th], -1)


def rollout(nets, TP, TQ6, h, glo, gup, ostar, valid=None, hidden=(None, None, None), record=True):
    """Eq. (2) over T frames. TP [B, T, 3, 3], TQ6 [B, T, 3, 6] world trackers; h [B, 3], glo [B, 122],
    gup [B, 144], ostar [B, 27] (o* for the first frame, in frame h). valid [B, T, 3] bool: a missing
    controller is replaced by o* (paper §8.2). Returns per-frame dicts of tensors [B, T, ...]."""
    sig, lo, up = nets
    hs, hl, hu = hidden
    out = {k: [] for k in ("z", "glo", "gup", "h", "ostar", "ysig_n", "ylo_n", "yup_n")}
    for t in range(TP.shape[1]):
        P, Q6 = TP[:, t], TQ6[:, t]
        if valid is not None:
            Ps, Qs = L.tracker_world(h, ostar)
            m = valid[:, t][..., None]
            P, Q6 = torch.where(m, P, Ps), torch.where(m, Q6, Qs)
        # z~^t = G_sig(inv(h^{t-1}) (x) o^t)
        z, zn, hs = sig(L.tracker_input(h, P, Q6)[:, None], hs)
        z = z[:, 0]
        # (z*^{t+1}, g_lo^t) = G_lo(z~^t, g_lo^{t-1})
        y, yln, hl = lo(torch.cat([z, glo], -1)[:, None], hl)
        glo = y[:, 0, :L.N_GLO]
        # h^t = h^{t-1} (x) dh^t, dh^t in g_lo^t
        h = L.compose(h, glo[:, L.DH_IN_GLO:L.DH_IN_GLO + 3])
        # (o*^{t+1}, g_up^t) = G_up(inv(h^t) (x) o^t, g_up^{t-1})
        y, yun, hu = up(torch.cat([L.tracker_input(h, P, Q6), gup], -1)[:, None], hu)
        gup, ostar = y[:, 0, :L.N_GUP], y[:, 0, L.N_GUP:]
        if record:
            for k, v in (("z", z), ("glo", glo), ("gup", gup), ("h", h), ("ostar", ostar),
                         ("ysig_n", zn[:, 0]), ("ylo_n", yln[:, 0]), ("yup_n", yun[:, 0])):
                out[k].append(v)
    return {k: torch.stack(v, 1) for k, v in out.items() if v}, (hs, hl, hu), (h, glo, gup, ostar)


def world_pose(h, glo, gup):
    """Full-body pose from the states: hips position and world rotations R_j = R_y(theta) R(q_j) of all 21
    joints, then FK positions with the standard offsets. Returns (positions [..., 21, 3], rotations
    [..., 21, 3, 3])."""
    k_lo, k_up = len(L.J_LO), len(L.J_UP)
    q = torch.zeros(*h.shape[:-1], 21, 6, dtype=h.dtype)
    q[..., L.I_LO, :] = glo[..., 6 * k_lo:12 * k_lo].reshape(*h.shape[:-1], k_lo, 6)
    q[..., L.I_UP, :] = gup[..., 6 * k_up:12 * k_up].reshape(*h.shape[:-1], k_up, 6)
    R = L.rot6_to_matrix(L.rot6(h, q))
    hips = L.point(h, glo[..., None, 0:3])[..., 0, :]
    off = L.offsets(h.dtype)
    P = [None] * 21
    for j, par in enumerate(L.PARENTS):
        P[j] = hips if par < 0 else P[par] + torch.einsum("...ij,j->...i", R[..., par, :, :], off[j])
    return torch.stack(P, -2), R
