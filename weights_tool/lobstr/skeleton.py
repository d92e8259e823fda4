"""Skeletons: joint-name mapping across skeletons, the standard skeleton, tracker synthesis, contacts.

The standard skeleton is the one of the training data (Bandai Namco, 21 joints from Hips). Other
skeletons (e.g. CMU) are mapped onto it by joint names (ROLE_NAMES) and scaled by leg length.

Tracker frames (the convention shared with C++ features/calibration.hpp):
  pelvis   position of the hips joint (where the standard skeleton has it: standard_hips_point; the
           rig's own root on the training clips); orientation W_hips F_local, F_local = the frame built from
           the rest offsets: Y = up (hips -> first spine joint away from the hips), X = left (left
           minus right thigh root, made orthogonal), Z = X x Y = forward. Rigid with the hips joint,
           so a bending lower back (CMU's LowerBack/Spine) does not tilt it.
  head, hands  joint position; orientation Q_k(t) o_k with o_k = Q_k(t0)^T Yaw(F_hips(t0)): at the
           calibration frame t0 every tracker points along the body's facing frame (paper §4.2: the
           rotational offsets are found in a calibration pose).
"""
import re

import numpy as np

from . import bvh
from .rotations import axis_angle, random_rotations, yaw_frame

# role -> accepted joint names (normalized: norm_name), tried in order; C++ twin pose/joint_map.hpp
# (keep equal): wrists before hands and ankles before feet (SMPL names its ankle L_Ankle and its toe
# L_Foot), a toe falling back to a foot name no other role took.
ROLE_NAMES = {
    "hips": ["hips", "pelvis", "hip"],
    "spine": ["spine", "lowerback", "spine1", "spine01", "abdomen", "waist"],
    "head": ["head"],
    "hand_l": ["lwrist", "leftwrist", "wristl", "handl", "lefthand", "lhand"],
    "hand_r": ["rwrist", "rightwrist", "wristr", "handr", "righthand", "rhand"],
    "upleg_l": ["upperlegl", "leftupleg", "lthigh", "leftthigh", "thighl", "leftupperleg", "lupperleg", "lhip", "lefthip"],
    "upleg_r": ["upperlegr", "rightupleg", "rthigh", "rightthigh", "thighr", "rightupperleg", "rupperleg", "rhip", "righthip"],
    "leg_l": ["lowerlegl", "leftleg", "lshin", "leftshin", "shinl", "leftlowerleg", "llowerleg", "lcalf", "calfl", "lknee",
              "leftknee"],
    "leg_r": ["lowerlegr", "rightleg", "rshin", "rightshin", "shinr", "rightlowerleg", "rlowerleg", "rcalf", "calfr", "rknee",
              "rightknee"],
    "foot_l": ["lankle", "leftankle", "anklel", "footl", "leftfoot", "lfoot"],
    "foot_r": ["rankle", "rightankle", "ankler", "footr", "rightfoot", "rfoot"],
    "toe_l": ["toesl", "lefttoebase", "lefttoe", "ltoe", "ltoes", "lefttoes", "ltoebase", "toel", "ltoe0", "balll", "footl",
              "leftfoot", "lfoot"],
    "toe_r": ["toesr", "righttoebase", "righttoe", "rtoe", "rtoes", "righttoes", "rtoebase", "toer", "rtoe0", "ballr", "footr",
              "rightfoot", "rfoot"],
}
# a rig's name prefix, dropped by norm_name (the longer of two that share a start first)
RIG_PREFIXES = ("bip001", "bip01", "ccbase", "jbipc", "jbip", "def")
TRACKED = ["head", "hand_l", "hand_r"]          # order of the three joints in the features
# The 8 predicted lower-body joints (paper §3: 8 x 6D), standard-skeleton names.
LOWER = ["UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"]
STANDARD_LEG = ("LowerLeg_L", "Foot_L")          # thigh and shin bones: leg length for height scaling
# The standard skeleton's hips joint: on the pelvis's up axis, this many leg lengths above the
# midpoint of the thigh roots (2.19 cm on its 80.07 cm leg). C++ twin: pose/joint_map.hpp.
STANDARD_HIPS_ABOVE_THIGH_ROOTS = 2.19248 / (39.0811 + 40.9854)


def norm_name(n):
    """The part after the last ':' (a namespace), lower case, alphanumerics only, without a rig's prefix."""
    n = re.sub(r"[^a-z0-9]", "", n.rsplit(":", 1)[-1].lower())
    for p in RIG_PREFIXES:
        if len(n) > len(p) and n.startswith(p):
            return n[len(p):]
    return n


def map_roles(names):
    """role -> joint index, by names (pose/joint_map.hpp's rule: exact names first, then, for a role
    still without a joint, a name ending with a candidate of 4 or more characters; a joint takes one
    role); raises ValueError listing missing roles."""
    nn_ = [norm_name(n) for n in names]
    out, taken = {}, set()
    for suffix in (False, True):
        for role, cands in ROLE_NAMES.items():
            for c in cands:
                if role in out:
                    break
                if suffix and len(c) < 4:
                    continue
                for j, n in enumerate(nn_):
                    if j not in taken and (n.endswith(c) if suffix else n == c):
                        out[role] = j
                        taken.add(j)
                        break
    missing = [r for r in ROLE_NAMES if r not in out and r != "spine"]
    if missing:
        raise ValueError("cannot map joints by name: no joint for " + ", ".join(missing))
    return out


def leg_length(b, roles):
    """Thigh + shin length in the file's units."""
    return float(np.linalg.norm(b.offsets[roles["leg_l"]]) + np.linalg.norm(b.offsets[roles["foot_l"]]))


def spine_base(b, roles):
    """The joint that gives the pelvis its up axis: the lowest joint on the way from the hips to the
    head whose rest position is away from the hips (> 5 % of the leg; CMU's LowerBack sits on the hips)."""
    chain, j = [], roles["head"]
    while j != roles["hips"]:
        if j < 0:
            raise ValueError("the head is not below the hips")
        chain.append(j)
        j = b.parents[j]
    min_len = 0.05 * leg_length(b, roles)
    for j in reversed(chain):
        if np.linalg.norm(rest_offset(b, j, roles["hips"])) > min_len:
            return j
    return chain[0]


def rest_offset(b, j, ancestor):
    """Rest position of joint j relative to `ancestor` (sum of offsets along the chain)."""
    v = np.zeros(3)
    while j != ancestor:
        v = v + np.asarray(b.offsets[j])
        j = b.parents[j]
    return v


def hips_local_frame(b, roles):
    """F_local: the tracker frame of the pelvis in hips-local coordinates (X left, Y up, Z forward)."""
    h = roles["hips"]
    up = rest_offset(b, spine_base(b, roles), h)
    left = rest_offset(b, roles["upleg_l"], h) - rest_offset(b, roles["upleg_r"], h)
    return frame_from(up, left)


def standard_hips_point(b, roles):
    """Where the standard skeleton's hips joint lies on this rig, hips-local rest coordinates in the
    file's units: the thigh roots' midpoint plus STANDARD_HIPS_ABOVE_THIGH_ROOTS leg lengths along the
    pelvis's up axis; zero within 0.6 % of the leg (5 mm) of the rig's own hips joint (every training
    clip). CMU's root sits at the lower back, ~10 cm above and behind it. C++ twin:
    pose::standard_hips_point."""
    h = roles["hips"]
    leg = leg_length(b, roles)
    mid = 0.5 * (rest_offset(b, roles["upleg_l"], h) + rest_offset(b, roles["upleg_r"], h))
    p = mid + hips_local_frame(b, roles)[:, 1] * (STANDARD_HIPS_ABOVE_THIGH_ROOTS * leg)
    return np.zeros(3) if not np.linalg.norm(p) >= 0.006 * leg or not np.isfinite(p).all() else p


def frame_from(up, left):
    y = up / np.linalg.norm(up)
    x = left - np.dot(left, y) * y
    x = x / np.linalg.norm(x)
    return np.stack([x, y, np.cross(x, y)], axis=-1)


def unit_scale(b, roles):
    """Metres per file unit, guessed from the leg length (a human leg is 0.6-1.1 m): cm, m, or other."""
    leg = leg_length(b, roles)
    for s in (0.01, 1.0, 0.0254, 0.001):
        if 0.5 < leg * s < 1.2:
            return s
    return 0.85 / leg


def up_axis_turn(b, roles, R_local, t_local, min_share=0.7):
    """The rotation [3, 3] that turns a clip whose world is not Y-up (AMASS / SMPL exports, Z-up
    scenes) to +Y, or None: on up to 240 frames spread over the clip, the signed axis nearest to
    the hips -> head direction; when one other than +Y holds at least min_share of them, the shortest
    rotation from it to +Y (a half turn about X for -Y). Twin of recordings/bvh_up_axis.hpp."""
    F = R_local.shape[0]
    n = min(F, 240)
    if n <= 0:
        return None
    f = (np.arange(n) * (F - 1)) // (n - 1) if n > 1 else np.zeros(1, dtype=int)
    _, pw = bvh.fk(b.parents, R_local[f], t_local[f])
    d = pw[:, roles["head"]] - pw[:, roles["hips"]]
    d = d[np.isfinite(d).all(axis=1) & (np.einsum("ij,ij->i", d, d) > 0)]
    if len(d) == 0:
        return None
    a = np.abs(d).argmax(axis=1)
    k = 2 * a + (d[np.arange(len(d)), a] < 0)
    votes = np.bincount(k, minlength=6)
    best = int(votes.argmax())
    if best == 2 or votes[best] < min_share * len(d):
        return None
    if best == 3:
        return np.diag([1.0, -1.0, -1.0])
    u = np.zeros(3)
    u[best // 2] = 1.0 if best % 2 == 0 else -1.0
    axis = np.cross(u, [0.0, 1.0, 0.0])
    return axis_angle(axis / np.linalg.norm(axis), 90.0)  # the shortest turn from u to +Y


class Clip:
    """A BVH clip in metres with its roles, world transforms and local rotations."""

    def __init__(self, path_or_bvh, units=None):
        self.bvh = b = bvh.load(path_or_bvh) if isinstance(path_or_bvh, str) else path_or_bvh
        self.roles = map_roles(b.names)
        self.units = units if units is not None else unit_scale(b, self.roles)
        R, t = bvh.local_transforms(b)
        t = t * self.units
        T = up_axis_turn(b, self.roles, R, t)
        if T is not None:  # the file's world is not Y-up: the roots' rotations and positions turned
            roots = [j for j, p in enumerate(b.parents) if p < 0]
            R[:, roots] = T @ R[:, roots]
            t[:, roots] = t[:, roots] @ T.T
        self.up_turn = T
        self.R_local, self.t_local = R, t
        self.Rw, self.pw = bvh.fk(b.parents, R, t)
        self.fps = 1.0 / b.frame_time
        self.leg = leg_length(b, self.roles) * self.units
        self.F_local = hips_local_frame(b, self.roles)
        self.hips_point = standard_hips_point(b, self.roles) * self.units  # the pelvis tracker's place, hips-local

    @property
    def frames(self):
        return self.Rw.shape[0]

    def floor(self):
        """Floor height: low percentile of the toe heights minus the standard toe-joint height."""
        r = self.roles
        y = np.concatenate([self.pw[:, r["toe_l"], 1], self.pw[:, r["toe_r"], 1]])
        return float(np.percentile(y, 2)) - 0.042 * self.leg / 0.80

    def trackers(self, t0=0):
        """Synthetic tracker world poses: positions [F, 4, 3] and rotations [F, 4, 3, 3] in the order
        head, hand_l, hand_r, pelvis (features.TRACKER_ORDER)."""
        r = self.roles
        # pelvis frame rigid with the hips joint (rest geometry): follows the pelvis, not the lower back
        Fh = self.Rw[:, r["hips"]] @ self.F_local
        yaw0 = yaw_frame(Fh[t0, :, 2])
        P = np.empty((self.frames, 4, 3))
        Q = np.empty((self.frames, 4, 3, 3))
        for k, role in enumerate(TRACKED):
            j = r[role]
            o = self.Rw[t0, j].T @ yaw0
            P[:, k], Q[:, k] = self.pw[:, j], self.Rw[:, j] @ o
        P[:, 3], Q[:, 3] = self.pw[:, r["hips"]] + self.Rw[:, r["hips"]] @ self.hips_point, Fh
        return P, Q


def add_tracker_noise(rng, P, Q, pos_std=0.01, rot_max_deg=1.5):
    """Paper Appendix 2: per frame, a random vector of length ~ |N(0, 0.01)| m on positions and a
    random rotation of at most 1.5 degrees on orientations."""
    F, K = P.shape[:2]
    d = rng.normal(size=(F, K, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    P = P + d * np.abs(rng.normal(0.0, pos_std, size=(F, K, 1)))
    Q = Q @ random_rotations(rng, F * K, rot_max_deg).reshape(F, K, 3, 3)
    return P, Q


def contact_labels(clip, floor, height=0.02, speed=0.6):
    """Toe-base contact [F, 2] (left, right): toe joint within `height` m of its standing height and
    slower than `speed` m/s horizontally (the paper uses height alone; speed removes swing-phase grazes)."""
    r = clip.roles
    toe_h = floor + 0.042 * clip.leg / 0.80
    out = np.zeros((clip.frames, 2), dtype=np.int64)
    for s, role in enumerate(("toe_l", "toe_r")):
        p = clip.pw[:, r[role]]
        v = np.zeros(clip.frames)
        v[1:] = np.linalg.norm(np.diff(p[:, [0, 2]], axis=0), axis=-1) * clip.fps
        v[0] = v[1] if clip.frames > 1 else 0.0
        out[:, s] = (p[:, 1] < toe_h + height) & (v < speed)
    return out
