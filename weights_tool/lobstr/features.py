"""The 37 LoBSTr input features (paper Appendix 1), reference implementation (numpy, float64).

Tracker order: head, hand_l, hand_r, pelvis. Inputs are calibrated tracker world poses (metres,
+Y up, floor at y = 0) and the height scale s (standard skeleton / user), applied to positions.

Reference joint (paper §3): at the pelvis on the ground, Y up, Z = ground projection of the pelvis
forward axis (its yaw is held when the pelvis axis is vertical). With (q_ref, p_ref) and per tracked
joint (q, p) at frame i, all expressed in the current reference frame:
  v_ref = q_ref,i^-1 (p_ref,i - p_ref,i-1)          w_ref = 6D(q_ref,i-1^-1 q_ref,i)
  p'    = q_ref^-1 (p - p_ref)  (each frame its own reference)
  v     = p'_i - p'_i-1                               w = 6D(q'_i-1^-1 q'_i),  q' = q_ref^-1 q
  x_i   = [v_ref, w_ref, (v, w) head, (v, w) hand_l, (v, w) hand_r, p_ref,y]   (4 x 9 + 1 = 37)
Velocities are per model frame. At the first frame (or after a reset) the previous frame is the
current one, so velocities are zero and rotations the identity.
"""
import numpy as np

from .rotations import to6d, yaw_frame

TRACKER_ORDER = ["head", "hand_l", "hand_r", "pelvis"]
N_FEATURES = 37


def reference_frames(P, Q, scale):
    """Reference rotation [F, 3, 3] and position [F, 3] from the (scaled) pelvis tracker."""
    pp = P[:, 3] * scale
    pr = pp.copy()
    pr[:, 1] = 0.0
    return yaw_frame(Q[:, 3, :, 2]), pr


def features(P, Q, scale=1.0):
    """P [F, 4, 3], Q [F, 4, 3, 3] -> X [F, 37]."""
    F = P.shape[0]
    Rr, pr = reference_frames(P, Q, scale)
    Rr_prev = np.concatenate([Rr[:1], Rr[:-1]])
    pr_prev = np.concatenate([pr[:1], pr[:-1]])
    RrT = np.swapaxes(Rr, -1, -2)
    RrT_prev = np.swapaxes(Rr_prev, -1, -2)
    X = np.empty((F, N_FEATURES))
    X[:, 0:3] = np.einsum("fij,fj->fi", RrT, pr - pr_prev)
    X[:, 3:9] = to6d(RrT_prev @ Rr)
    for k in range(3):
        p = P[:, k] * scale
        pl = np.einsum("fij,fj->fi", RrT, p - pr)
        pl_prev = np.concatenate([pl[:1], pl[:-1]])
        Rl = RrT @ Q[:, k]
        Rl_prev = np.concatenate([Rl[:1], Rl[:-1]])
        o = 9 + 9 * k
        X[:, o:o + 3] = pl - pl_prev
        X[:, o + 3:o + 9] = to6d(np.swapaxes(Rl_prev, -1, -2) @ Rl)
    X[:, 36] = P[:, 3, 1] * scale
    return X
