"""Device-realistic training data (issue 12): bodies of many sizes, playback speeds and trackers that
sit where real devices sit, as the C++ runtime sees them after its calibration.

The device model is the C++ one (include/sparsebody/features/device_model.hpp; keep equal). Offsets are
in a tracker's *calibrated frame* R_cal = q o (X left, Y up, Z forward of the body at the calibration
frame), metres, absolute:
  headset = head joint + R_cal e,   e = (0, 0.08, 0.10)     (OpenXR view pose between the eyes)
  grip    = wrist joint + R_cal g,  g = (0, -0.08, 0.03)    (relaxed standing grip)
The runtime subtracts the *nominal* offsets, so a network sees joint estimates
  p^ = p_joint + R_cal d_user - (R_cal E) d_nominal,   q^ = R_cal E
with the user's own offsets d_user and the calibration's rotational error E (the standing frame the
runtime calibrates on is not the training clips' first frame). Height scale as the runtime finds it:
s = standard standing head-joint height / (standing eye height - e_y).

Per clip (`Augment`): stature 1.5-1.95 m with independent leg / torso / arm ratios (+-8 %), root height
scaled with the legs so the feet stay on the floor; playback speed 0.8-1.2x (local rotations resampled,
root translation interpolated); eye offset +-2 cm per axis; grip offsets 5-12 cm long, direction within
30 deg of nominal; calibration error up to 10 deg (headset, pelvis) / 25 deg (controllers); a belt
tracker up to 4 cm off the hips joint, then moved along its up axis so that at the calibration frame
it sits at the standard standing hips height (the runtime's pelvis calibration: belt placement and
proportions do not read as a crouch); per-frame timing jitter (2 ms: the resampler interpolates 72-90 Hz
samples at jittered times, an error of v * dt) and short tracking losses (1-6 model frames, ~1 per 10 s
per controller) held as the sanitizer holds them (trackers/sanitizer.hpp). Mirroring is not done.
"""
import copy

import numpy as np

from .lobstr import bvh
from .lobstr.rotations import random_rotations
from .lobstr.skeleton import TRACKED, add_tracker_noise
from .lobstr.standard import STANDARD

EYE = np.array([0.0, 0.08, 0.10])
GRIP = np.array([0.0, -0.08, 0.03])
NOMINAL = [EYE, GRIP, GRIP]                   # head, hand_l, hand_r
# The standard performer's pelvis tracker frame at standing relative to the facing frame (chordal
# mean over every 5th training clip's first frame: a ~3 deg tilt; per clip it varies by 4.5 deg
# median around this). The runtime calibrates a belt tracker, whatever its mounting, to this frame at
# the standing frame (C++ DeviceModel::pelvis_standing); the device realisations do the same.
PELVIS_STANDING = np.array([[0.9996, 0.0299, 0.0], [-0.0298, 0.9986, 0.0435], [0.0013, -0.0434, 0.9991]])
EYE_TO_STATURE = 0.936                        # eye height / stature (Winter, Fig. 4.1; Drillis & Contini 1966)
# the standard performer's stature by that ratio (standing head joint + eye offset)
STANDARD_STATURE = (STANDARD["standing_head_height"] + EYE[1]) / EYE_TO_STATURE

LEG = ("LowerLeg_L", "Foot_L", "Toes_L", "LowerLeg_R", "Foot_R", "Toes_R")
TORSO = ("Spine", "Chest", "Neck", "Head", "Shoulder_L", "Shoulder_R", "UpperArm_L", "UpperArm_R",
         "UpperLeg_L", "UpperLeg_R")
ARM = ("LowerArm_L", "Hand_L", "LowerArm_R", "Hand_R")


class Augment:
    """One clip's random body, speed and device errors."""

    def __init__(self, rng, body=True, speed=True, devices=True):
        self.rng = rng
        u = rng.uniform
        self.stature = u(1.5, 1.95) if body else STANDARD_STATURE
        self.leg, self.torso, self.arm = (u(0.92, 1.08, 3) if body else np.ones(3))
        self.speed = u(0.8, 1.2) if speed else 1.0
        self.devices = devices
        if devices:
            self.eye = EYE + u(-0.02, 0.02, 3)
            self.grip = [_grip(rng), _grip(rng)]
            self.err = [random_rotations(rng, 1, d)[0] for d in (10.0, 25.0, 25.0, 10.0)]
            self.belt = _ball(rng, 0.04)
            self.scale_err = 1.0 + u(-0.015, 0.015)
        else:
            self.eye, self.grip, self.err, self.belt, self.scale_err = EYE, [GRIP, GRIP], [np.eye(3)] * 4, np.zeros(3), 1.0


def _ball(rng, r):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v) * r * rng.uniform() ** (1 / 3)


def _grip(rng):
    d = GRIP / np.linalg.norm(GRIP)
    d = random_rotations(rng, 1, 30.0)[0] @ d
    return d * rng.uniform(0.05, 0.12)


def orthonormal(R):
    u, _, vt = np.linalg.svd(R)
    d = np.sign(np.linalg.det(u @ vt))
    u[..., :, -1] *= d[..., None]
    return u @ vt


def retime(clip, speed):
    """The clip played `speed` times faster (frame rate unchanged): rotations blended linearly between
    the two nearest frames and re-orthonormalised, translations interpolated."""
    if abs(speed - 1.0) < 1e-9:
        return clip
    F = clip.frames
    n = max(2, int(np.floor((F - 1) / speed)) + 1)
    tau = np.minimum(np.arange(n) * speed, F - 1)
    i0 = np.floor(tau).astype(int)
    i1 = np.minimum(i0 + 1, F - 1)
    a = (tau - i0)[:, None, None]
    out = copy.copy(clip)
    out.R_local = orthonormal((1 - a[..., None]) * clip.R_local[i0] + a[..., None] * clip.R_local[i1])
    out.t_local = (1 - a) * clip.t_local[i0] + a * clip.t_local[i1]
    out.Rw, out.pw = bvh.fk(clip.bvh.parents, out.R_local, out.t_local)
    return out


def scale_body(clip, aug):
    """Segment lengths scaled (stature / the standard performer's, then leg / torso / arm ratios); the
    root translation follows the legs so the feet stay on the floor."""
    k = aug.stature / STANDARD_STATURE
    b = clip.bvh
    f = np.full(len(b.names), k)
    for names, r in ((LEG, aug.leg), (TORSO, aug.torso), (ARM, aug.arm)):
        for n in names:
            if n in b.names:
                f[b.index(n)] = k * r
    out = copy.copy(clip)
    t = clip.t_local * f[None, :, None]
    hips = clip.roles["hips"]
    j = hips
    while j >= 0:                      # the root chain down to the hips carries the pelvis height
        t[:, j] = clip.t_local[:, j] * k * aug.leg
        j = b.parents[j]
    out.t_local = t
    out.Rw, out.pw = bvh.fk(b.parents, clip.R_local, t)
    out.leg = clip.leg * k * aug.leg
    return out


def device_trackers(clip, aug, noise=True):
    """Tracker poses [F, 4, 3], [F, 4, 3, 3] (head, hand_l, hand_r, pelvis; floor at y = 0) as the
    runtime's calibration turns the devices into joint estimates, and the scale s it finds."""
    rng = aug.rng
    floor = clip.floor()
    P, Q = clip.trackers()
    P = P.copy()
    P[..., 1] -= floor
    eye_y = P[0, 0, 1] + (Q[0, 0] @ aug.eye)[1]
    user = [aug.eye, aug.grip[0], aug.grip[1]]
    Qe = Q @ np.stack(aug.err)[None]
    for k in range(3):
        P[:, k] += np.einsum("fij,j->fi", Q[:, k], user[k]) - np.einsum("fij,j->fi", Qe[:, k], NOMINAL[k])
    P[:, 3] += np.einsum("fij,j->fi", Q[:, 3], aug.belt)
    if aug.devices:
        # the belt tracker calibrated at the calibration frame (its mounting is unknown): the facing
        # frame (the headset's, Q[0, 0]) times the standard standing tilt, then the calibration error
        Qe[:, 3] = Q[:, 3] @ (Q[0, 3].T @ Q[0, 0] @ orthonormal(PELVIS_STANDING)) @ aug.err[3]
    Q = Qe
    s = STANDARD["standing_head_height"] / max(eye_y - EYE[1], 0.3) * aug.scale_err
    # the runtime calibration puts a belt tracker at the standard standing hips height (in the
    # standard scale) at the calibration frame: an offset along the calibrated pelvis's up axis
    d = Q[0, 3].T @ np.array([0.0, P[0, 3, 1] - STANDARD["standing_hips_height"] / s, 0.0])
    P[:, 3] -= np.einsum("fij,j->fi", Q[:, 3], d)
    if noise:
        P, Q = add_tracker_noise(rng, P, Q)
    if aug.devices:
        v = np.gradient(P, axis=0) * clip.fps if len(P) > 2 else np.zeros_like(P)
        P = P + v * rng.normal(0.0, 0.002, size=(len(P), 4, 1))
        rate = 0.1 / clip.fps                  # loss events per frame per tracker
        for k in (1, 2, 3, 0):
            if k == 0:
                rate = 0.02 / clip.fps
            for f in np.nonzero(rng.uniform(size=len(P)) < rate)[0]:
                if f == 0:
                    continue
                e = min(len(P), f + int(rng.integers(1, 7)))
                P[f:e, k], Q[f:e, k] = P[f - 1, k], Q[f - 1, k]
    return P, Q, s
