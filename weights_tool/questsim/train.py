"""PPO training of the QuestSim torque policy on this machine's CPUs (Winkler et al. 2022, §3.7,
Appendix A), in the batched C++ environment (weights_tool/questsim/env.py -> questsim_env.hpp).

  nice -n 10 /usr/bin/python3 -m weights_tool.questsim.train TRAIN_DIR --out OUT [--resume]

What follows the paper: policy and value MLPs [400, 300, 200] tanh (the policy's output tanh too, as
the run-time network: a in [-1, 1] -> 200 N m), the imitation reward with its weights and kernels,
5 epochs over 4 minibatches per update, reference-state initialisation. What a 2-core CPU forces:
a few hundred characters instead of 4000, the motions headset users make (--motions, default the
standing gestures and walks of the training split), and optionally a residual root force that
helps the character stay up early and is annealed to zero (--residual-force N over
--residual-anneal samples); the shipped policy is measured with it off.
Exploration noise: a learned state-independent log std, started at --init-std (the paper's fixed
0.03 needs its 14 billion steps).
Warm start (--bc-iters K): the first K updates are DAgger (Ross et al. 2011) on the environment's
privileged expert (computed-torque tracking of the reference with the feet carrying the root's
wrench, questsim_env.hpp; --expert-wn, --expert-support-height): each step a
character executes the expert's action with probability beta (1 -> 0 over the K updates), else the
policy's sample; the policy regresses the expert's action on every visited observation, the value
function learns the returns as in PPO. PPO follows.
--task n3p trains the Neural3Points correction policy instead (issue 14 item 4, the issue's fallback to
the paper's full policy): the environment is include/sparsebody/training/n3p_env.hpp (the physics
mode's avatar and model-based controller; the policy adds a correction of at most --action-scale rad
to each PD target every 30 Hz frame; observation s = {x_t, g_t+1..3}, 1008 values), the networks
[256, 256] tanh (the paper's policy width), the export OUT/n3p_correction_policy.json (kind
"n3p_correction_policy"); --residual-force / --residual-torque start the controller's residual wrench
bound (the pipeline's default is 620 N / 250 N m) and anneal it to zero. DAgger, heights and neutral
starts are QuestSim's only.
Everything is resumable: OUT/checkpoint.pt (policy, value, optimiser, observation statistics,
iteration, random state), OUT/curve.csv (one row per update), OUT/curve.png, and the policy in the
library's format OUT/questsim_policy.json (kind "questsim_policy", normalisation = the running
observation statistics) written with every checkpoint.
"""
import argparse
import csv
import glob
import math
import os
import re
import time

# One BLAS thread unless the caller says otherwise: with --threads 1 the run used 164 % CPU, numpy's
# OpenBLAS starting its own threads (torch.set_num_threads does not reach it). Set before numpy loads.
for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np
import torch
import torch.nn as tnn

from .. import nets
from ..format import read_weights, write_weights
from .env import ROOT, load_module
from .policy import HIDDEN

DEFAULT_MOTIONS = r"raise-up|wave|bye|bow|guide|call|respond|walk"
CREDIT = "Bandai Namco Research Motion Dataset, Bandai Namco Research Inc., CC BY-NC 4.0"
NON_COMMERCIAL = "Weights trained on the Bandai Namco Research Motion Dataset (CC BY-NC 4.0): non-commercial use only."


class RunningStats:
    """Per-feature mean / variance over every observation seen (Chan et al. parallel update)."""

    def __init__(self, n):
        self.n, self.mean, self.m2 = 0, np.zeros(n), np.zeros(n)

    def update(self, x):
        x = np.asarray(x, np.float64).reshape(-1, self.mean.size)
        nb, mb = x.shape[0], x.mean(0)
        m2b = ((x - mb) ** 2).sum(0)
        d, tot = mb - self.mean, self.n + nb
        self.mean = self.mean + d * nb / tot
        self.m2 = self.m2 + m2b + d * d * self.n * nb / tot
        self.n = tot

    def std(self, floor):
        return np.maximum(np.sqrt(self.m2 / max(self.n - 1, 1)), floor)

    def state(self):
        return {"n": self.n, "mean": self.mean, "m2": self.m2}

    def load(self, s):
        self.n, self.mean, self.m2 = s["n"], s["mean"], s["m2"]


N3P_HIDDEN = (256, 256)  # the paper's policy width (§5)


class ActorCritic(tnn.Module):
    def __init__(self, n_obs, n_act, init_std, hidden=HIDDEN, kind="questsim_policy"):
        super().__init__()
        self.actor = nets.MLPPolicy([n_obs, *hidden, n_act], "tanh", "tanh", kind)
        self.critic = nets.MLPPolicy([n_obs, *hidden, 1], "tanh", "identity", "value")
        with torch.no_grad():  # small first actions (a few N m), as PPO implementations start
            self.actor.layers[-1].weight.mul_(0.01)
            self.actor.layers[-1].bias.zero_()
        self.log_std = tnn.Parameter(torch.full((n_act,), math.log(init_std)))

    def dist(self, x):
        mu, _ = self.actor(x)
        return torch.distributions.Normal(mu, self.log_std.clamp(math.log(0.01), math.log(1.0)).exp())

    def value(self, x):
        v, _ = self.critic(x)
        return v.squeeze(-1)


def pick_clips(train_dir, motions, limit):
    paths = sorted(glob.glob(os.path.join(train_dir, "*.bvh")))
    rx = re.compile(motions)
    paths = [p for p in paths if rx.search(os.path.basename(p)) and "not-confident" not in p]
    if limit:
        paths = paths[::max(1, len(paths) // limit)][:limit]
    if not paths:
        raise SystemExit(f"no training clips in {train_dir} match {motions!r}")
    return paths


def export(path, model, stats, n_obs, n_act, info):
    mean = stats.mean.astype(np.float32)
    std = stats.std(0.05).astype(np.float32)
    mean[-1], std[-1] = 1.75, 1.0  # o_user,scale: the user's height varies at run time, not in training
    meta = {"frame_rate": 36, "paper": "QuestSim (Winkler et al. 2022), Appendix A", "random_weights": False,
            "trained": True, "bodies": 21, "joint_dofs": n_act, "future_frames": 6,
            "output": "tanh in [-1, 1], times each joint's torque limit (control/questsim_actuation.hpp) = joint torques", "credit": CREDIT, "license": "CC BY-NC 4.0",
            "non_commercial": NON_COMMERCIAL, **info}
    write_weights(path, nets.export_state_dict(model.actor), "questsim_policy", n_obs, n_act, meta=meta,
                  normalization={"input_mean": mean, "input_std": std})


def export_n3p(path, model, stats, n_obs, n_act, info):
    meta = {"frame_rate": 30, "paper": "Neural3Points (Ye et al. 2022) physics mode: a correction of the model-based "
            "controller's PD targets (issue 14 item 4 fallback)", "random_weights": False, "trained": True,
            "joint_dofs": n_act, "input": "s = {x_t, g_t+1, g_t+2, g_t+3} (control/n3p_policy_input.hpp)",
            "output": "tanh in [-1, 1], times action_scale (rad) = the correction of each joint DoF's PD target",
            "credit": CREDIT, "license": "CC BY-NC 4.0", "non_commercial": NON_COMMERCIAL, **info}
    write_weights(path, nets.export_state_dict(model.actor), "n3p_correction_policy", n_obs, n_act, meta=meta,
                  normalization={"input_mean": stats.mean.astype(np.float32), "input_std": stats.std(0.05).astype(np.float32)})


def load_policy_tensors(path, doc, tensors, actor, kind, n_obs, n_act):
    """Loads an exported policy's tensors (read_weights) into actor after checking that the file is
    a `kind` of n_obs -> n_act with the actor's own tensors (SystemExit naming the file otherwise)."""
    meta = doc.get("meta", {})
    if doc.get("kind") != kind or meta.get("input_size") != n_obs or meta.get("output_size") != n_act:
        raise SystemExit(f"{path}: expected a {kind} {n_obs} -> {n_act}, found {doc.get('kind')} "
                         f"{meta.get('input_size')} -> {meta.get('output_size')}")
    own = actor.state_dict()
    if set(own) != set(tensors):
        raise SystemExit(f"{path}: tensors {sorted(tensors)} do not match the policy's {sorted(own)}")
    actor.load_state_dict({k: torch.tensor(v, dtype=own[k].dtype).reshape(own[k].shape) for k, v in tensors.items()})


def init_from_json(path, model, stats, n_obs, n_act, kind="questsim_policy"):
    """Loads an exported policy (export() above) into model.actor and stats; returns (iteration, samples).
    The checkpoint's optimiser state and critic are not in the export: Adam and the critic start afresh."""
    doc, tensors, norm = read_weights(path)
    meta = doc.get("meta", {})
    load_policy_tensors(path, doc, tensors, model.actor, kind, n_obs, n_act)
    n = int(meta.get("samples", 1_000_000))
    std = np.asarray(norm["input_std"], np.float64)
    stats.n, stats.mean = n, np.asarray(norm["input_mean"], np.float64)
    stats.m2 = std * std * (n - 1)
    return int(meta.get("iterations", 0)), n


def plot(curve_csv, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = list(csv.DictReader(open(curve_csv)))
    if len(rows) < 2:
        return
    x = np.array([float(r["samples"]) for r in rows]) / 1e6
    fig, ax = plt.subplots(1, 3, figsize=(14, 4))
    ax[0].plot(x, [float(r["reward"]) for r in rows], label="mean reward / step")
    for k in ("r_q", "r_qd", "r_x", "r_xd", "r_f"):
        ax[0].plot(x, [float(r[k]) for r in rows], lw=0.7, label=k)
    ax[0].set_xlabel("samples (M)"); ax[0].legend(fontsize=7); ax[0].set_title("reward")
    ax[1].plot(x, [float(r["episode_steps"]) for r in rows])
    ax[1].set_xlabel("samples (M)"); ax[1].set_title("mean episode length (control steps)")
    ax[2].plot(x, [float(r["residual"]) for r in rows], label="residual bound (N)")
    ax[2].plot(x, [float(r["residual_used"]) for r in rows], label="residual used, mean (N)")
    ax[2].set_xlabel("samples (M)"); ax[2].legend(fontsize=7); ax[2].set_title("root residual force")
    fig.tight_layout(); fig.savefig(png, dpi=90); plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="weights_tool.questsim.train")
    ap.add_argument("train_dir")
    ap.add_argument("--out", required=True)
    ap.add_argument("--resume", action="store_true")
    ap.add_argument("--init-json", default="",
                    help="start from a policy in the library's format (its weights, observation statistics, samples "
                         "and iterations); the value function starts afresh: see --value-warmup")
    ap.add_argument("--value-warmup", type=int, default=0,
                    help="updates that train only the value function (after --init-json, so that a fresh critic's "
                         "advantages do not undo the policy)")
    ap.add_argument("--motions", default=DEFAULT_MOTIONS, help="regex on clip names")
    ap.add_argument("--clips", type=int, default=0, help="use this many clips (0: all matching)")
    ap.add_argument("--envs", type=int, default=128)
    ap.add_argument("--horizon", type=int, default=32)
    ap.add_argument("--samples", type=float, default=50e6, help="stop after this many control steps")
    ap.add_argument("--hours", type=float, default=0, help="stop after this wall time (0: no limit)")
    ap.add_argument("--lr", type=float, default=1e-4)
    ap.add_argument("--gamma", type=float, default=0.95)
    ap.add_argument("--lam", type=float, default=0.95)
    ap.add_argument("--epochs", type=int, default=5)
    ap.add_argument("--minibatches", type=int, default=4)
    ap.add_argument("--init-std", type=float, default=0.05)
    ap.add_argument("--residual-force", type=float, default=0.0, help="N at the start (0: none)")
    ap.add_argument("--residual-torque", type=float, default=0.0, help="N m at the start")
    ap.add_argument("--residual-anneal", type=float, default=20e6, help="samples to anneal it to 0")
    ap.add_argument("--bc-iters", type=int, default=0, help="DAgger updates before PPO")
    ap.add_argument("--expert-wn", type=float, default=15.0, help="rad/s: the expert's tracking frequency")
    ap.add_argument("--expert-support-height", type=float, default=0.02,
                    help="m: feet this close to the floor carry the expert's root wrench (0: no stance support)")
    ap.add_argument("--armature", type=float, default=0.05,
                    help="kg m^2 of rotor inertia on every joint DoF (dynamics::Body::armature; QuestSimConfig::joint_armature "
                         "must match at run time: 0.05 there by default)")
    ap.add_argument("--neutral-start", type=float, default=0.25,
                    help="share of episodes started in the pipeline's reset pose (neutral, at rest, under the headset)")
    ap.add_argument("--max-head-error", type=float, default=0.5, help="m: an episode ends when the head is this far off the reference")
    ap.add_argument("--heights", type=float, nargs=2, default=[1.45, 1.95], metavar=("LO", "HI"),
                    help="m: the characters' heights, evenly spaced over [LO, HI] (the clip retargeted to each; "
                         "o_user,scale): the run-time avatar is sized to each user (1.75 1.75: runs 1-7's single size)")
    ap.add_argument("--threads", type=int, default=1, help="torch threads")
    ap.add_argument("--env-threads", type=int, default=1)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--n3p-lower", default=os.path.join(ROOT, "examples/weights/n3p_lower.json"))
    ap.add_argument("--task", choices=("questsim", "n3p"), default="questsim",
                    help="questsim: the torque policy; n3p: the Neural3Points correction policy (n3p_env.hpp)")
    ap.add_argument("--action-scale", type=float, default=0.2, help="n3p: rad of PD-target correction per unit action")
    ap.add_argument("--residual-weight", type=float, default=0.2,
                    help="n3p: reward weight of exp(-|residual force| / body weight)")
    a = ap.parse_args(argv)
    n3p = a.task == "n3p"
    if n3p and a.bc_iters:
        raise SystemExit("--task n3p: no DAgger (--bc-iters)")
    torch.set_num_threads(a.threads)
    torch.manual_seed(a.seed)
    os.makedirs(a.out, exist_ok=True)
    qe = load_module()
    paths = pick_clips(a.train_dir, a.motions, a.clips)
    clips = qe.load_clips(paths, a.n3p_lower, 30.0 if n3p else 36.0)
    cfg = qe.N3PConfig() if n3p else qe.Config()
    if n3p:
        cfg.action_scale = a.action_scale
        cfg.residual_weight = a.residual_weight
        env = qe.N3PEnv(clips, a.envs, a.seed, cfg)
        n_obs, n_act = qe.N3PEnv.obs_size, qe.N3PEnv.action_size
        model = ActorCritic(n_obs, n_act, a.init_std, N3P_HIDDEN, "n3p_correction_policy")
    else:
        cfg.joint_armature = a.armature
        cfg.neutral_start = a.neutral_start
        cfg.max_head_error = a.max_head_error
        cfg.expert = a.bc_iters > 0  # the privileged expert costs two RNEAs per step: only for DAgger
        cfg.expert_wn = a.expert_wn
        cfg.expert_support = a.expert_support_height > 0
        cfg.expert_support_height = max(a.expert_support_height, 1e-6)
        if not (0.5 < a.heights[0] <= a.heights[1] < 3.0):
            raise SystemExit(f"--heights {a.heights[0]} {a.heights[1]}: expected 0.5 < LO <= HI < 3 (m)")
        heights = np.linspace(a.heights[0], a.heights[1], a.envs)
        env = qe.Env(clips, [float(h) for h in np.random.default_rng(a.seed).permutation(heights)], a.seed, cfg)
        n_obs, n_act = qe.Env.obs_size, qe.Env.action_size
        model = ActorCritic(n_obs, n_act, a.init_std)
    opt = torch.optim.Adam(model.parameters(), lr=a.lr)
    stats = RunningStats(n_obs)
    it, samples = 0, 0
    ckpt = os.path.join(a.out, "checkpoint.pt")
    if a.resume and os.path.exists(ckpt):
        s = torch.load(ckpt, weights_only=False)
        model.load_state_dict(s["model"]); opt.load_state_dict(s["opt"]); stats.load(s["stats"])
        it, samples = s["iteration"], s["samples"]
        torch.set_rng_state(s["torch_rng"])
        print(f"resumed at iteration {it}, {samples / 1e6:.2f} M samples", flush=True)
    elif a.init_json:
        it, samples = init_from_json(a.init_json, model, stats, n_obs, n_act, "n3p_correction_policy" if n3p else "questsim_policy")
        print(f"policy from {a.init_json} ({samples / 1e6:.2f} M samples, iteration {it}); value function afresh, "
              f"{a.value_warmup} value-only updates first", flush=True)
    it_start = it
    curve = os.path.join(a.out, "curve.csv")
    fields = ["iteration", "samples", "wall_s", "reward", "r_q", "r_qd", "r_x", "r_xd", "r_f", "episode_steps",
              "terminations", "residual", "residual_used", "std", "policy_loss", "value_loss", "steps_per_s"]
    if not (a.resume and os.path.exists(curve)):
        with open(curve, "w", newline="") as f:
            csv.writer(f).writerow(fields)
    print(f"{a.task}: {len(paths)} clips ({a.motions}), {a.envs} characters"
          f"{'' if n3p else f' of {a.heights[0]:.2f}-{a.heights[1]:.2f} m'}, obs {n_obs}, actions {n_act}", flush=True)
    t_start = time.time()
    N, T = a.envs, a.horizon
    ep_len = np.zeros(N)
    while samples < a.samples and (a.hours <= 0 or time.time() - t_start < a.hours * 3600):
        frac = min(1.0, samples / a.residual_anneal) if a.residual_anneal > 0 else 1.0
        res_f, res_t = a.residual_force * (1 - frac), a.residual_torque * (1 - frac)
        env.set_residual(res_f, res_t)
        mean_t = torch.tensor(stats.mean, dtype=torch.float32) if stats.n else torch.zeros(n_obs)
        std_np = stats.std(0.05) if stats.n else np.ones(n_obs)
        if not n3p:  # o_user,scale: the user's height varies at run time, not in training
            std_np[-1] = 1.0
        std_t = torch.tensor(std_np, dtype=torch.float32)
        if stats.n and not n3p:
            mean_t[-1] = 1.75
        norm = lambda x: (torch.from_numpy(np.asarray(x, np.float32)) - mean_t) / std_t
        obs = np.zeros((T, N, n_obs), np.float32)
        act = np.zeros((T, N, n_act), np.float32)
        logp = np.zeros((T, N), np.float32)
        rew = np.zeros((T, N), np.float32)
        val = np.zeros((T + 1, N), np.float32)
        term = np.zeros((T, N), np.float32)
        trunc_v = np.zeros((T, N), np.float32)  # V(final obs) of truncated episodes
        done = np.zeros((T, N), np.float32)
        bc = it < a.bc_iters
        beta = 1.0 - it / max(a.bc_iters, 1) if bc else 0.0
        expert = np.zeros((T, N, n_act), np.float32) if bc else None
        rng = np.random.default_rng(a.seed * 100003 + it)
        terms = np.zeros(5)
        used, ended, lens = 0.0, 0, []
        t0 = time.time()
        env_s = 0.0
        with torch.no_grad():
            for t in range(T):
                o = env.obs.copy()
                obs[t] = o
                x = norm(o)
                d = model.dist(x)
                u = d.sample()
                act[t] = u.numpy()
                if bc:
                    expert[t] = env.expert_actions
                    use = rng.random(N) < beta
                    act[t, use] = expert[t, use]
                logp[t] = d.log_prob(u).sum(-1).numpy()
                val[t] = model.value(x).numpy()
                te = time.time()
                env.step(act[t], a.env_threads)
                env_s += time.time() - te
                rew[t] = env.reward
                term[t] = env.terminated
                tr = env.truncated.astype(bool)
                done[t] = np.maximum(env.terminated, env.truncated)
                if tr.any():
                    trunc_v[t, tr] = model.value(norm(env.final_obs[tr])).numpy()
                terms += env.reward_terms[:, :5].mean(0)
                used += float(env.reward_terms[:, 5].mean()) if n3p else float(np.mean([env.residual_force(i) for i in range(0, N, 8)]))
                ep_len += 1
                for i in np.nonzero(done[t])[0]:
                    lens.append(ep_len[i]); ep_len[i] = 0
                ended += int(env.terminated.sum())
            val[T] = model.value(norm(env.obs)).numpy()
        stats.update(obs.reshape(-1, n_obs))
        # GAE: a terminated step has no future; a truncated one bootstraps from its final observation.
        adv = np.zeros((T, N), np.float32)
        last = np.zeros(N, np.float32)
        for t in reversed(range(T)):
            nxt = np.where(done[t] > 0, trunc_v[t] * (1 - term[t]), val[t + 1])
            delta = rew[t] + a.gamma * nxt - val[t]
            last = delta + a.gamma * a.lam * (1 - done[t]) * last
            adv[t] = last
        ret = adv + val[:T]
        B = T * N
        xb = norm(obs.reshape(B, n_obs)); ab = torch.from_numpy(act.reshape(B, n_act))
        lpb = torch.from_numpy(logp.reshape(B)); advb = torch.from_numpy(adv.reshape(B))
        advb = (advb - advb.mean()) / (advb.std() + 1e-8)
        retb = torch.from_numpy(ret.reshape(B))
        mb = B // a.minibatches
        pl_sum = vl_sum = 0.0
        eb = torch.from_numpy(expert.reshape(B, n_act)) if bc else None
        for _ in range(a.epochs):
            perm = torch.randperm(B)
            for k in range(a.minibatches):
                idx = perm[k * mb:(k + 1) * mb]
                d = model.dist(xb[idx])
                if it - it_start < a.value_warmup:  # a fresh critic learns the returns; the policy waits
                    pl = torch.zeros(())
                elif bc:  # regress the expert's action (the policy's mean; its noise is left as is)
                    pl = ((d.mean - eb[idx]) ** 2).mean()
                else:
                    ratio = (d.log_prob(ab[idx]).sum(-1) - lpb[idx]).exp()
                    pl = -torch.min(ratio * advb[idx], ratio.clamp(0.8, 1.2) * advb[idx]).mean()
                vl = ((model.value(xb[idx]) - retb[idx]) ** 2).mean()
                loss = pl + 0.5 * vl
                opt.zero_grad(); loss.backward()
                tnn.utils.clip_grad_norm_(model.parameters(), 1.0)
                opt.step()
                pl_sum += float(pl); vl_sum += float(vl)
        it += 1
        samples += B
        nupd = a.epochs * a.minibatches
        row = [it, samples, round(time.time() - t_start, 1), float(rew.mean()), *(terms / T), float(np.mean(lens)) if lens else T,
               ended, res_f, used / T, float(model.log_std.exp().mean()), pl_sum / nupd, vl_sum / nupd, B / max(env_s, 1e-9)]
        with open(curve, "a", newline="") as f:
            csv.writer(f).writerow([f"{v:.6g}" if isinstance(v, float) else v for v in row])
        if it % 10 == 0 or samples >= a.samples:
            print(f"{'dagger beta %.2f ' % beta if bc else ''}it {it} samples {samples / 1e6:.2f}M reward {rew.mean():.4f} ep {row[9]:.1f} residual {res_f:.0f} N "
                  f"std {row[13]:.3f} env {row[16]:.0f} steps/s iter {time.time() - t0:.1f}s", flush=True)
            torch.save({"model": model.state_dict(), "opt": opt.state_dict(), "stats": stats.state(), "iteration": it,
                        "samples": samples, "torch_rng": torch.get_rng_state(), "args": vars(a)}, ckpt + ".tmp")
            os.replace(ckpt + ".tmp", ckpt)
            if n3p:
                export_n3p(os.path.join(a.out, "n3p_correction_policy.json"), model, stats, n_obs, n_act,
                           {"samples": samples, "iterations": it, "motions": a.motions, "clips": len(paths),
                            "residual_at_export": [res_f, res_t], "action_scale": a.action_scale})
            else:
                export(os.path.join(a.out, "questsim_policy.json"), model, stats, n_obs, n_act,
                       {"samples": samples, "iterations": it, "motions": a.motions, "clips": len(paths),
                        "residual_at_export": res_f, "joint_armature": a.armature, "heights_m": list(a.heights)})
            plot(curve, os.path.join(a.out, "curve.png"))


if __name__ == "__main__":
    main()
