"""A learned world model of the QuestSim character and a policy trained through it (SuperTrack:
Fussell, Bergamin and Holden 2021), on this machine's CPUs (issue 14: the next step after PPO's
plateau).

  /usr/bin/python3 -m weights_tool.questsim.worldmodel collect TRAIN_DIR --out DIR [--policy P.json] [--steps T]
  /usr/bin/python3 -m weights_tool.questsim.worldmodel fit DIR [--minutes M] [--window W]
  /usr/bin/python3 -m weights_tool.questsim.worldmodel errors DIR [--model M.pt] [--json OUT]
  /usr/bin/python3 -m weights_tool.questsim.worldmodel plot DIR -o CURVE.png
  /usr/bin/python3 -m weights_tool.questsim.worldmodel policy DIR [--minutes M] [--horizon H] [--init P.json] [--anchor B]

What differs from the paper, and why:
- The state is the character block of the policy's own observation (joint angles and rates, link
  positions, 6D rotations, linear and angular velocities in the floor heading frame S, foot forces:
  417 values; layout.py), not world-space rigid bodies: the policy's input is then rebuilt from the
  model's prediction without any kinematics, and the model is heading-invariant by construction.
  The rollout also carries where S is in the world (yaw and origin), so that the user's sensor
  frames, which are given in the world, can be re-expressed in the predicted S, and the character's
  place in the world can be compared with the reference's.
- As in SuperTrack the network gives velocity changes and the positions and rotations are
  integrated (trapezoid rule, plus a small learned correction, since joint angles are rotation
  vectors); the new S is the one the predicted root pose defines. A first version that predicted
  the next state directly was worse than extrapolating at constant velocity (one-step link error
  3.1 cm against 1.9 cm) after 35 minutes of fitting.
- Rounds of collect -> fit (--resume) -> policy, each policy starting from the shipped PPO one
  (a round's data: --name data2.npz ...; every DIR/data*.npz is used), instead of SuperTrack's
  continual data gathering. The README's QuestSim training section has what two rounds gave.
Data: the training environment (questsim_env.hpp) with `record_reference` (the reference state as an
observation of the same layout, and the heading frames), driven by a policy plus Gaussian noise of
a per-character scale. Never committed: DIR lives outside the repository.
Losses are L1 on features divided by their spread in the data (SuperTrack's choice), weights below.
"""
import argparse
import json
import math
import os
import time

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np
import torch
import torch.nn as tnn

from .. import nets
from ..format import read_weights, write_weights
from .env import ROOT, load_module
from .layout import layout
from .policy import HIDDEN
from .train import CREDIT, DEFAULT_MOTIONS, NON_COMMERCIAL, load_policy_tensors, pick_clips

L = layout(21, 48, 6)
CH = L["user"]            # 417: q, qd, x, R6, xd, w, foot forces
NU = L["height"] - CH     # 189: 7 frames x 3 devices x (p, r6)
NA = 48
SHIPPED = os.path.join(ROOT, "examples/weights/questsim_policy.json")
# Feature groups of the character block and their loss weights (policy training).
GROUPS = {"q": (L["q"], L["qd"], 1.0), "qd": (L["qd"], L["x"], 0.2), "x": (L["x"], L["R"], 1.0),
          "R": (L["R"], L["xd"], 1.0), "xd": (L["xd"], L["w"], 0.3), "w": (L["w"], L["f"], 0.3)}


def load_policy(path):
    doc, tensors, norm = read_weights(path)
    m = nets.MLPPolicy([L["size"], *HIDDEN, NA], "tanh", "tanh", "questsim_policy")
    load_policy_tensors(path, doc, tensors, m, "questsim_policy", L["size"], NA)
    return m, (torch.tensor(norm["input_mean"], dtype=torch.float32), torch.tensor(norm["input_std"], dtype=torch.float32)), doc


def make_env(qe, train_dir, n, seed, motions=DEFAULT_MOTIONS):
    paths = pick_clips(train_dir, motions, 0)
    clips = qe.load_clips(paths, os.path.join(ROOT, "examples/weights/n3p_lower.json"), 36.0)
    cfg = qe.Config()
    cfg.joint_armature = 0.05
    cfg.neutral_start = 0.25
    cfg.max_head_error = 1.0
    cfg.record_reference = True
    heights = np.random.default_rng(seed).permutation(np.linspace(1.45, 1.95, n))
    return qe.Env(clips, [float(h) for h in heights], seed, cfg), heights


# ---------------------------------------------------------------------------------------------- collect
def collect(a):
    torch.set_num_threads(a.threads)
    qe = load_module()
    env, heights = make_env(qe, a.train_dir, a.envs, a.seed)
    pol, (mu, sd), _ = load_policy(a.policy)
    rng = np.random.default_rng(a.seed)
    noise = rng.uniform(a.noise[0], a.noise[1], size=(a.envs, 1)).astype(np.float32)
    T, N = a.steps, a.envs
    S = np.zeros((T + 1, N, CH), np.float32)      # state at t (after any restart)
    U = np.zeros((T + 1, N, NU), np.float32)      # user frames t..t+6 in S_t
    R = np.zeros((T + 1, N, CH), np.float32)      # reference state at t, its own frame
    F = np.zeros((T + 1, N, 8), np.float32)       # frames: sim (c, s, ox, oz), reference
    A = np.zeros((T, N, NA), np.float32)
    END = np.zeros((T, N), np.uint8)              # 0 goes on, 1 failed substep, 2 fall, 3 lost, 4 nan, 9 truncated
    SN = np.zeros((T, N, CH), np.float32)         # the next state of the same episode (final obs where it ended)
    FN = np.zeros((T, N, 4), np.float32)
    t0 = time.time()
    for t in range(T):
        o = env.obs
        S[t], U[t], R[t], F[t] = o[:, :CH], o[:, CH:L["height"]], env.reference_obs[:, :CH], env.frames
        with torch.no_grad():
            x = (torch.from_numpy(o) - mu) / sd
            act = pol(x)[0].numpy()
        act = np.clip(act + noise * rng.standard_normal(act.shape).astype(np.float32), -1, 1).astype(np.float32)
        A[t] = act
        env.step(np.ascontiguousarray(act), a.env_threads)
        term, trunc = env.terminated.copy(), env.truncated.copy()
        END[t] = np.where(term > 0, term, np.where(trunc > 0, 9, 0))
        ended = END[t] > 0
        SN[t] = np.where(ended[:, None], env.final_obs[:, :CH], env.obs[:, :CH])
        FN[t] = np.where(ended[:, None], env.final_frames[:, :4], env.frames[:, :4])
        if t % 200 == 0:
            print(f"collect {t}/{T} {time.time() - t0:.0f}s ends/step {ended.mean():.3f}", flush=True)
    o = env.obs
    S[T], U[T], R[T], F[T] = o[:, :CH], o[:, CH:L["height"]], env.reference_obs[:, :CH], env.frames
    os.makedirs(a.out, exist_ok=True)
    np.savez(os.path.join(a.out, a.name), S=S, U=U, R=R, F=F, A=A, END=END, SN=SN, FN=FN,
             H=np.asarray(heights, np.float32), noise=noise[:, 0])
    ends = END[END > 0]
    print(f"collected {T * N} transitions in {time.time() - t0:.0f}s: failed {np.mean(ends == 1) if ends.size else 0:.3f} "
          f"fall {np.sum(ends == 2)} lost {np.sum(ends == 3)} truncated {np.sum(ends == 9)}", flush=True)


# ----------------------------------------------------------------------------------------- world model
def frame_delta(f0, f1):
    """(dtheta, dx, dz) of frame f1 in frame f0, frames (c, s, ox, oz): the vector in f0's axes."""
    th0, th1 = torch.atan2(f0[..., 1], f0[..., 0]), torch.atan2(f1[..., 1], f1[..., 0])
    d = torch.remainder(th1 - th0 + math.pi, 2 * math.pi) - math.pi
    dx, dz = f1[..., 2] - f0[..., 2], f1[..., 3] - f0[..., 3]
    c, s = f0[..., 0], f0[..., 1]
    return torch.stack([d, c * dx - s * dz, s * dx + c * dz], -1)


def frame_apply(f0, d):
    """Frame f0 (c, s, ox, oz) moved by d = (dtheta, dx, dz) in f0's axes -> (c, s, ox, oz)."""
    c, s = f0[..., 0], f0[..., 1]
    th = torch.atan2(s, c) + d[..., 0]
    # R_y(theta) v = (c x + s z, y, -s x + c z)
    ox = f0[..., 2] + c * d[..., 1] + s * d[..., 2]
    oz = f0[..., 3] - s * d[..., 1] + c * d[..., 2]
    return torch.stack([torch.cos(th), torch.sin(th), ox, oz], -1)


def reexpress_user(u, fr, fp):
    """User block u (..., 189) given in frame fr -> the same sensor frames in frame fp."""
    sh = u.shape
    u = u.reshape(*sh[:-1], 21, 9)
    cr, sr, cp, sp = fr[..., 0, None], fr[..., 1, None], fp[..., 0, None], fp[..., 1, None]
    # relative yaw R_p^T R_r = R_y(theta_r - theta_p)
    c = cr * cp + sr * sp
    s = sr * cp - cr * sp

    def rot(x, z):  # R_y(th) (x, z)
        return c * x + s * z, -s * x + c * z
    px, pz = rot(u[..., 0], u[..., 2])
    # + R_p^T (o_r - o_p)
    dx, dz = fr[..., 2] - fp[..., 2], fr[..., 3] - fp[..., 3]
    ox, oz = cp[..., 0] * dx - sp[..., 0] * dz, sp[..., 0] * dx + cp[..., 0] * dz
    px, pz = px + ox[..., None], pz + oz[..., None]
    ax, az = rot(u[..., 3], u[..., 5])
    bx, bz = rot(u[..., 6], u[..., 8])
    out = torch.stack([px, u[..., 1], pz, ax, u[..., 4], az, bx, u[..., 7], bz], -1)
    return out.reshape(sh)


DT = 1.0 / 36.0  # one control step


def _rotate(v, phi):
    """Rodrigues: vectors v (..., 3) rotated by rotation vectors phi (..., 3)."""
    th = torch.sqrt((phi * phi).sum(-1, keepdim=True) + 1e-12)
    k = phi / th
    c, s = torch.cos(th), torch.sin(th)
    return v * c + torch.linalg.cross(k, v, dim=-1) * s + k * (k * v).sum(-1, keepdim=True) * (1 - c)


def _yaw_T(v, c, s):
    """R_y(theta)^T v for vectors (..., 3), c = cos theta, s = sin theta broadcast over (...)."""
    return torch.stack([c * v[..., 0] - s * v[..., 2], v[..., 1], s * v[..., 0] + c * v[..., 2]], -1)


class WorldModel(tnn.Module):
    """(s_t, a_t) -> (s_t+1, motion of S), integrated as SuperTrack does: the network gives the change
    of every velocity (links' linear and angular, joints' rates) and the next foot forces, in the old
    frame S_t; positions and rotations follow by the trapezoid rule (plus a small learned
    correction); the new S_t+1 is the one the new root pose defines (QuestSimFloorFrame: yaw of the
    root's forward axis, origin under it), and everything is re-expressed in it."""

    OUT = 63 + 63 + 48 + 63 + 48 + 6  # dxd, dw, dqd, x correction, q correction, next foot forces

    def __init__(self, stats, hidden=(512, 512, 512)):
        super().__init__()
        sizes = [CH + NA + 1, *hidden, self.OUT]
        self.layers = tnn.ModuleList(tnn.Linear(x, y) for x, y in zip(sizes[:-1], sizes[1:]))
        for k, v in stats.items():
            self.register_buffer(k, torch.as_tensor(v, dtype=torch.float32))
        d = self.ds_std
        scale = torch.cat([d[L["xd"]:L["w"]], d[L["w"]:L["f"]], d[L["qd"]:L["x"]], 0.1 * d[L["x"]:L["R"]],
                           0.1 * d[L["q"]:L["qd"]], self.s_std[L["f"]:CH]])
        self.register_buffer("out_scale", scale)
        with torch.no_grad():
            self.layers[-1].weight.mul_(0.1)
            self.layers[-1].bias.zero_()

    def forward(self, s, a, h):
        """h: the character's height (m), (..., 1): the same torques move a smaller body faster."""
        x = torch.cat([(s - self.s_mean) / self.s_std, a, (h - 1.7) / 0.15], -1)
        for i, l in enumerate(self.layers):
            x = l(x)
            if i + 1 < len(self.layers):
                x = torch.nn.functional.elu(x)
        y = x * self.out_scale
        B = s.shape[:-1]
        g = lambda lo, hi: s[..., L[lo]:L[hi]]
        q, qd = g("q", "qd"), g("qd", "x")
        xp, R6 = g("x", "R").reshape(*B, 21, 3), g("R", "xd").reshape(*B, 21, 6)
        v, w = g("xd", "w").reshape(*B, 21, 3), g("w", "f").reshape(*B, 21, 3)
        o = 0
        def take(n):
            nonlocal o
            o += n
            return y[..., o - n:o]
        v1 = v + take(63).reshape(*B, 21, 3)
        w1 = w + take(63).reshape(*B, 21, 3)
        qd1 = qd + take(48)
        x1 = xp + 0.5 * DT * (v + v1) + take(63).reshape(*B, 21, 3)
        q1 = q + 0.5 * DT * (qd + qd1) + take(48)
        f1 = take(6).reshape(*B, 2, 3)
        phi = 0.5 * DT * (w + w1)
        c0, c1 = _rotate(R6[..., :3], phi), _rotate(R6[..., 3:], phi)
        c0 = c0 / torch.linalg.norm(c0, dim=-1, keepdim=True)
        c1 = c1 - (c0 * c1).sum(-1, keepdim=True) * c0
        c1 = c1 / torch.linalg.norm(c1, dim=-1, keepdim=True)
        # S_t+1 in S_t: yaw of the root's forward axis (third column), origin under the root
        fwd = torch.linalg.cross(c0[..., 0, :], c1[..., 0, :], dim=-1)
        th = torch.atan2(fwd[..., 0], fwd[..., 2])
        dx, dz = x1[..., 0, 0], x1[..., 0, 2]
        c, sn = torch.cos(th)[..., None], torch.sin(th)[..., None]
        off = torch.stack([dx, torch.zeros_like(dx), dz], -1)[..., None, :]
        x1 = _yaw_T(x1 - off, c, sn)
        c0, c1, v1, w1 = _yaw_T(c0, c, sn), _yaw_T(c1, c, sn), _yaw_T(v1, c, sn), _yaw_T(w1, c, sn)
        f1 = _yaw_T(f1, c, sn)
        out = torch.cat([q1, qd1, x1.flatten(-2), torch.cat([c0, c1], -1).flatten(-2), v1.flatten(-2), w1.flatten(-2),
                         f1.flatten(-2)], -1)
        return out, torch.stack([th, dx, dz], -1)


STATS = ("s_mean", "s_std", "ds_std")


def load_worldmodel(path):
    ck = torch.load(path)
    wm = WorldModel({k: ck["model"][k].numpy() for k in STATS})
    wm.load_state_dict(ck["model"])
    return wm, ck["iteration"]


def load_data(d):
    """DIR/data*.npz (one per collection round, the same number of steps), characters side by side."""
    import glob
    parts = [np.load(p) for p in sorted(glob.glob(os.path.join(d, "data*.npz")))]
    if not parts:
        raise SystemExit(f"{d}: no data*.npz (run collect first)")
    return {k: np.concatenate([z[k] for z in parts], axis=0 if k in ("H", "noise") else 1) for k in parts[0].files}


def windows(END, W, allow_last_end=True):
    """(t, i) starts of W-step windows inside one episode (an end only at the last step, and never a failed substep)."""
    T, N = END.shape
    e = (END > 0).astype(np.int32)
    c = np.concatenate([np.zeros((1, N), np.int32), np.cumsum(e, 0)])  # c[t] = ends before t
    span = W - 1 if allow_last_end else W
    ok = (c[span:T - W + 1 + span] - c[:T - W + 1]) == 0
    if allow_last_end:
        ok &= END[W - 1:, :] != 1
    t, i = np.nonzero(ok)
    return t, i


def stats_of(D):
    S, SN, END = D["S"], D["SN"], D["END"]
    good = END != 1
    s = S[:-1][good]
    ds = (SN - S[:-1])[good]
    return {"s_mean": s.mean(0), "s_std": np.maximum(s.std(0), 1e-3),
            "ds_std": np.maximum(ds.std(0), 1e-4)}


def rollout_model(wm, S0, F0, A, h):
    """Roll the model over actions A (B, W, NA) from S0 (B, CH), F0 (B, 4), heights h (B, 1): states (B, W, CH), frames (B, W, 4)."""
    s, f, ss, fs = S0, F0, [], []
    for k in range(A.shape[1]):
        s, df = wm(s, A[:, k], h)
        f = frame_apply(f, df)
        ss.append(s); fs.append(f)
    return torch.stack(ss, 1), torch.stack(fs, 1)


def wm_loss(wm, D, t, i, W):
    S, SN, F, FN, A = D["S"], D["SN"], D["F"], D["FN"], D["A"]
    idx = t[:, None] + np.arange(W)[None]
    S0 = torch.from_numpy(S[t, i]); F0 = torch.from_numpy(F[t, i, :4])
    Aw = torch.from_numpy(A[idx, i[:, None]])
    St = torch.from_numpy(SN[idx, i[:, None]]); Ft = torch.from_numpy(FN[idx, i[:, None]])
    ps, pf = rollout_model(wm, S0, F0, Aw, torch.from_numpy(D["H"][i])[:, None])
    ls = ((ps - St).abs() / wm.s_std).mean()
    lf = ((pf[..., 2:] - Ft[..., 2:]).abs().mean() / 0.05 + (pf[..., :2] - Ft[..., :2]).abs().mean() / 0.05)
    return ls + 0.1 * lf, ls.item(), lf.item()


def fit(a):
    torch.set_num_threads(a.threads)
    torch.manual_seed(a.seed)
    D = load_data(a.dir)
    path = os.path.join(a.dir, "worldmodel.pt")
    if a.resume and os.path.exists(path):
        wm, it0 = load_worldmodel(path)
    else:
        wm, it0 = WorldModel(stats_of(D)), 0
    opt = torch.optim.Adam(wm.parameters(), lr=a.lr)
    T = D["END"].shape[0]
    # hold out the last 10 % of the collection's steps for validation
    cut = int(T * 0.9)
    t, i = windows(D["END"], a.window)
    tr, va = t + a.window <= cut, t >= cut
    ttr, itr, tva, iva = t[tr], i[tr], t[va], i[va]
    rng = np.random.default_rng(a.seed)
    vsel = rng.choice(len(tva), min(2048, len(tva)), replace=False)
    log = open(os.path.join(a.dir, "fit_log.csv"), "a")
    t0, it = time.time(), it0
    while time.time() - t0 < a.minutes * 60:
        b = rng.choice(len(ttr), a.batch)
        loss, ls, lf = wm_loss(wm, D, ttr[b], itr[b], a.window)
        opt.zero_grad(); loss.backward()
        tnn.utils.clip_grad_norm_(wm.parameters(), 1.0)
        opt.step(); it += 1
        if it % 200 == 0:
            with torch.no_grad():
                _, vs, vf = wm_loss(wm, D, tva[vsel], iva[vsel], a.window)
            print(f"it {it} {time.time() - t0:.0f}s train {ls:.4f}/{lf:.4f} val {vs:.4f}/{vf:.4f}", flush=True)
            log.write(f"{it},{time.time() - t0:.1f},{ls},{lf},{vs},{vf}\n"); log.flush()
            torch.save({"model": wm.state_dict(), "iteration": it}, path)
    torch.save({"model": wm.state_dict(), "iteration": it}, path)
    json.dump(report_errors(wm, D, tva, iva, rng), open(os.path.join(a.dir, "worldmodel_errors.json"), "w"), indent=1)


def report_errors(wm, D, tva, iva, rng, W=8):
    """1-step and W-step rollout errors on held-out windows, in the units that matter, beside two
    baselines on the same windows: nothing moves, and the same integrator with the network's output
    zeroed (every velocity held: constant-velocity extrapolation)."""
    import copy
    t, i = tva, iva
    sel = rng.choice(len(t), min(2048, len(t)), replace=False)
    t, i = t[sel], i[sel]
    # windows of length W that stay inside one episode
    e = D["END"]
    keep = np.array([not (e[tt:tt + W - 1, ii] > 0).any() and tt + W <= e.shape[0] for tt, ii in zip(t, i)])
    t, i = t[keep], i[keep]
    idx = t[:, None] + np.arange(W)[None]
    St, Ft = D["SN"][idx, i[:, None]], D["FN"][idx, i[:, None]]
    still = copy.deepcopy(wm)
    with torch.no_grad():
        still.layers[-1].weight.zero_(); still.layers[-1].bias.zero_()
    out = {"windows": int(len(t))}
    S0, F0 = D["S"][t, i], D["F"][t, i, :4]
    for name, m in (("model", wm), ("constant_velocity", still), ("no_change", None)):
        if m is None:
            ps, pf = np.repeat(S0[:, None], W, 1), np.repeat(F0[:, None], W, 1)
        else:
            with torch.no_grad():
                ps, pf = rollout_model(m, torch.from_numpy(S0), torch.from_numpy(F0), torch.from_numpy(D["A"][idx, i[:, None]]),
                                       torch.from_numpy(D["H"][i])[:, None])
            ps, pf = ps.numpy(), pf.numpy()
        for k in (0, W - 1):
            x = np.linalg.norm((ps[:, k, L["x"]:L["R"]] - St[:, k, L["x"]:L["R"]]).reshape(-1, 21, 3), axis=-1).mean()
            root = np.linalg.norm(pf[:, k, 2:] - Ft[:, k, 2:], axis=-1).mean()
            q = np.abs(ps[:, k, :L["qd"]] - St[:, k, :L["qd"]]).mean()
            out[f"{name}_step{k + 1}"] = {"link_position_cm": round(100 * float(x), 3), "root_xz_cm": round(100 * float(root), 3),
                                          "joint_rad": round(float(q), 4)}
    print(json.dumps(out), flush=True)
    return out


def errors(a):
    """The report of fit's end for a saved model, on the held-out last 10 % of the collection's steps."""
    torch.set_num_threads(a.threads)
    D = load_data(a.dir)
    wm, _ = load_worldmodel(a.model or os.path.join(a.dir, "worldmodel.pt"))
    T = D["END"].shape[0]
    t, i = windows(D["END"], 8)
    va = t >= int(T * 0.9)
    json.dump(report_errors(wm, D, t[va], i[va], np.random.default_rng(a.seed)), open(a.json, "w") if a.json else open(os.devnull, "w"), indent=1)


# ------------------------------------------------------------------------------------------ policy
def policy_train(a):
    torch.set_num_threads(a.threads)
    torch.manual_seed(a.seed)
    D = load_data(a.dir)
    wm, _ = load_worldmodel(os.path.join(a.dir, "worldmodel.pt"))
    for p in wm.parameters():
        p.requires_grad_(False)
    pol, (mu, sd), doc = load_policy(a.init)
    anchor, _, _ = load_policy(a.init)  # trust region: the model is only right near the data's actions
    for p in anchor.parameters():
        p.requires_grad_(False)
    out_pt = os.path.join(a.dir, "policy.pt")
    it = 0
    if a.resume and os.path.exists(out_pt):
        c = torch.load(out_pt)
        pol.load_state_dict(c["policy"]); it = c["iteration"]
    opt = torch.optim.Adam(pol.parameters(), lr=a.lr)
    H = a.horizon
    t, i = windows(D["END"], H + 1, allow_last_end=False)
    rng = np.random.default_rng(a.seed)
    Hgt = torch.from_numpy(D["H"])
    s_std = wm.s_std
    log = open(os.path.join(a.dir, "policy_log.csv"), "a")
    t0 = time.time()
    while time.time() - t0 < a.minutes * 60:
        b = rng.choice(len(t), a.batch)
        tt, ii = t[b], i[b]
        idx = tt[:, None] + np.arange(H + 1)[None]
        U = torch.from_numpy(D["U"][idx, ii[:, None]])
        Fr = torch.from_numpy(D["F"][idx, ii[:, None]])
        Rf = torch.from_numpy(D["R"][idx, ii[:, None]])
        s, f = torch.from_numpy(D["S"][tt, ii]), Fr[:, 0, :4]
        h = Hgt[ii][:, None]
        loss_s, loss_w, loss_a, loss_anchor = 0.0, 0.0, 0.0, torch.zeros(())
        for k in range(H):
            u = reexpress_user(U[:, k], Fr[:, k, :4], f)
            obs = torch.cat([s, u, h], -1)
            xin = (obs - mu) / sd
            act = pol(xin)[0]
            if a.anchor > 0:
                loss_anchor = loss_anchor + (act - anchor(xin)[0]).pow(2).mean()
            act = (act + a.noise * torch.randn_like(act)).clamp(-1, 1)
            s, df = wm(s, act, h)
            f = frame_apply(f, df)
            ref, fref = Rf[:, k + 1], Fr[:, k + 1, 4:]
            for name, (lo, hi, w) in GROUPS.items():
                loss_s = loss_s + w * ((s[:, lo:hi] - ref[:, lo:hi]).abs() / s_std[lo:hi]).mean()
            dyaw = torch.atan2(f[:, 1] * fref[:, 0] - f[:, 0] * fref[:, 1], f[:, 0] * fref[:, 0] + f[:, 1] * fref[:, 1])
            loss_w = loss_w + (f[:, 2:] - fref[:, 2:]).abs().sum(-1).mean() / 0.1 + dyaw.abs().mean() / 0.2
            loss_a = loss_a + act.pow(2).mean()
        loss = (loss_s + a.world_weight * loss_w + a.action_weight * loss_a + a.anchor * loss_anchor) / H
        opt.zero_grad(); loss.backward()
        tnn.utils.clip_grad_norm_(pol.parameters(), 1.0)
        opt.step(); it += 1
        if it % 20 == 0:
            print(f"it {it} {time.time() - t0:.0f}s loss {loss.item():.4f} state {loss_s.item() / H:.4f} "
                  f"world {loss_w.item() / H:.4f} action {loss_a.item() / H:.4f} anchor {loss_anchor.item() / H:.5f}", flush=True)
            log.write(f"{it},{time.time() - t0:.1f},{loss.item()},{loss_s.item() / H},{loss_w.item() / H},{loss_a.item() / H},{loss_anchor.item() / H}\n"); log.flush()
        if it % 100 == 0:
            save_policy(a, pol, mu, sd, doc, it, out_pt)
        if it % a.snapshot == 0:  # for evaluations through the pipeline (evaluate.py) along the way
            os.makedirs(os.path.join(a.dir, "snapshots"), exist_ok=True)
            save_policy(a, pol, mu, sd, doc, it, out_pt, os.path.join(a.dir, "snapshots", f"policy_{it:06d}.json"))
    save_policy(a, pol, mu, sd, doc, it, out_pt)


def save_policy(a, pol, mu, sd, doc, it, out_pt, json_path=None):
    torch.save({"policy": pol.state_dict(), "iteration": it}, out_pt)
    meta = dict(doc.get("meta", {}))
    for k in ("input_size", "output_size"):
        meta.pop(k, None)
    meta.update({"worldmodel_iterations": it, "worldmodel_init": os.path.basename(a.init),
                 "training": "SuperTrack-style: backpropagation through a learned world model (weights_tool/questsim/worldmodel.py)",
                 "credit": CREDIT, "license": "CC BY-NC 4.0", "non_commercial": NON_COMMERCIAL})
    write_weights(json_path or os.path.join(a.dir, "questsim_policy_wm.json"), nets.export_state_dict(pol), "questsim_policy",
                  L["size"], NA, meta=meta, normalization={"input_mean": mu.numpy(), "input_std": sd.numpy()})


def plot(a):
    """fit_log.csv (world model: rollout loss on training batches and held-out windows) and
    policy_log.csv (policy: losses along the model's rollouts) -> one PNG."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 4))
    f = np.loadtxt(os.path.join(a.dir, "fit_log.csv"), delimiter=",", ndmin=2)
    ax[0].plot(f[:, 0], f[:, 2], lw=0.6, label="state, training batch")
    ax[0].plot(f[:, 0], f[:, 4], label="state, held-out windows")
    ax[0].set_xlabel("updates (256 windows of 8 steps)"); ax[0].set_ylabel("L1 / feature spread, mean over 8 steps")
    ax[0].set_title("world model"); ax[0].legend(fontsize=7)
    pp = os.path.join(a.dir, "policy_log.csv")
    if os.path.exists(pp):
        g = np.loadtxt(pp, delimiter=",", ndmin=2)
        for k, name in ((3, "state"), (4, "world (root place, yaw)"), (2, "total")):
            ax[1].plot(g[:, 0], g[:, k], lw=0.8, label=name)
        ax[1].set_xlabel("updates"); ax[1].set_title("policy through the model"); ax[1].legend(fontsize=7)
    fig.tight_layout(); fig.savefig(a.output, dpi=90); plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="weights_tool.questsim.worldmodel")
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("collect")
    c.add_argument("train_dir"); c.add_argument("--out", required=True)
    c.add_argument("--policy", default=SHIPPED)
    c.add_argument("--envs", type=int, default=192); c.add_argument("--steps", type=int, default=1200)
    c.add_argument("--noise", type=float, nargs=2, default=(0.02, 0.25))
    c.add_argument("--env-threads", type=int, default=2)
    c.add_argument("--name", default="data.npz", help="file under --out (data*.npz: every round is used by fit and policy)")
    f = sub.add_parser("fit")
    f.add_argument("dir"); f.add_argument("--minutes", type=float, default=20)
    f.add_argument("--window", type=int, default=8); f.add_argument("--batch", type=int, default=256)
    f.add_argument("--lr", type=float, default=3e-4); f.add_argument("--resume", action="store_true")
    p = sub.add_parser("policy")
    p.add_argument("dir"); p.add_argument("--minutes", type=float, default=30)
    p.add_argument("--init", default=SHIPPED); p.add_argument("--horizon", type=int, default=16)
    p.add_argument("--batch", type=int, default=128); p.add_argument("--lr", type=float, default=3e-5)
    p.add_argument("--noise", type=float, default=0.05)
    p.add_argument("--world-weight", type=float, default=1.0); p.add_argument("--action-weight", type=float, default=0.01)
    p.add_argument("--snapshot", type=int, default=500, help="keep a policy JSON every this many updates")
    p.add_argument("--anchor", type=float, default=0.0, help="weight of |pi(s) - pi_init(s)|^2 along the rollouts (a trust region)")
    p.add_argument("--resume", action="store_true")
    r = sub.add_parser("errors")
    r.add_argument("dir"); r.add_argument("--model", default=""); r.add_argument("--json", default="")
    g = sub.add_parser("plot")
    g.add_argument("dir"); g.add_argument("-o", "--output", required=True)
    for s in (c, f, p, r):
        s.add_argument("--threads", type=int, default=2); s.add_argument("--seed", type=int, default=1)
    a = ap.parse_args(argv)
    {"collect": collect, "fit": fit, "policy": policy_train, "plot": plot, "errors": errors}[a.cmd](a)


if __name__ == "__main__":
    main()
