"""Training (paper §4.1): pretrain G_sig, G_lo, G_up separately on features extracted from the motion
data (teacher forcing, small noise on the fed-back state), then fine-tune G_sig + G_lo jointly with G_up
frozen, on autoregressive rollouts of Eq. (2) (T = 60, batch 32, Adam 5e-4, dropout 0.1 / 0.05).

Losses (the L^mse terms are MSEs of the normalised outputs, i.e. weighted by 1 / sigma^2 per value):
  L_sig = L^mse_z~ + w_h L_h                                   (3)
  L_lo  = L^mse_{g_lo, z*} + w_h L_h + w_FK L_FK               (4)
  L_up  = L^mse_{g_up, o*} + w_FK L_FK                         (5)
  L_h   = mse_t[(p_x, p_z), gt] + mse_t[(sin th, cos th), gt]  (6), h accumulated from the predicted dh
Fine-tuning minimises L = L_sig + L_lo + L_up; in the rollout a quarter of the sequences run HMD-only
(controllers replaced by o*, §8.2) so that G_sig and G_lo also see that input.
CPU, one thread, a wall-clock budget per stage; checkpoints after every stage.
"""
import argparse
import sys
import time

import numpy as np
import torch

from . import layout as L
from .dataset import KEYS, Data
from .model import Sub, rollout, targets, world_pose

W_H, W_FK = 10.0, 100.0
NOISE = 0.05  # teacher-forcing noise on the fed-back state, in units of its std


def batch(data, rng, B, n):
    """B random chunks of n frames (clips picked in proportion to length), as torch tensors."""
    ok = np.nonzero(data.lens >= n)[0]
    p = data.lens[ok] / data.lens[ok].sum()
    idx = rng.choice(ok, size=B, p=p)
    st = np.array([data.starts[i] + rng.integers(0, data.lens[i] - n + 1) for i in idx])
    sel = st[:, None] + np.arange(n)[None]
    A = {k: torch.from_numpy(data.a[k][sel]) for k in KEYS}
    # tracker noise: about 5 mm per axis
    A["TP"] = A["TP"] + 0.005 * torch.randn_like(A["TP"])
    return A


def heading_loss(h, H):
    """L_h (6): h, H [B, T, 3]."""
    lp = ((h[..., :2] - H[..., :2]) ** 2).mean()
    la = ((torch.sin(h[..., 2]) - torch.sin(H[..., 2])) ** 2 + (torch.cos(h[..., 2]) - torch.cos(H[..., 2])) ** 2).mean() / 2
    return lp + la


def accumulate(h0, dh):
    hs, h = [], h0
    for t in range(dh.shape[1]):
        h = L.compose(h, dh[:, t])
        hs.append(h)
    return torch.stack(hs, 1)


def fk_loss(state, joints):
    return (L.fk_residual(state, joints) ** 2).sum(-1).mean()


def nmse(sub, y, target, sl=slice(None)):
    return (((y - target) / sub.out_std[sl]) ** 2).mean()


def set_normalization(nets, data, rng):
    """Means / stds of every input and output over teacher-forced training features."""
    A = batch(data, rng, 512, 8)
    F = targets(A, A["H"])
    cat = lambda *xs: torch.cat(xs, -1).reshape(-1, sum(x.shape[-1] for x in xs))
    ios = {"sig": (cat(F["sig_in"]), cat(F["z"])),
           "lo": (cat(F["z"][:, 1:], F["glo"][:, :-1]), cat(F["glo"], F["zn"])),
           "up": (cat(F["up_in"][:, 1:], F["gup"][:, :-1]), cat(F["gup"], F["onext"]))}
    for s in nets:
        x, y = ios[s.name]
        s.in_mean.copy_(x.mean(0)), s.in_std.copy_(x.std(0).clamp(min=1e-2))
        s.out_mean.copy_(y.mean(0)), s.out_std.copy_(y.std(0).clamp(min=1e-2))


def pretrain_step(sub, A, T):
    F = targets(A, A["H"])  # frames 1..T+1
    noise = lambda x, sl: x + NOISE * sub.in_std[sl] * torch.randn_like(x)
    H = A["H"][:, 2:T + 2]
    if sub.name == "sig":
        y, _, _ = sub(F["sig_in"][:, 1:])
        lh = heading_loss(accumulate(A["H"][:, 1], y[..., 9:12]), H)
        return nmse(sub, y, F["z"][:, 1:]) + W_H * lh, dict(h=lh.item())
    if sub.name == "lo":
        x = torch.cat([noise(F["z"][:, 1:], slice(0, L.N_Z)), noise(F["glo"][:, :-1], slice(L.N_Z, None))], -1)
        y, _, _ = sub(x)
        lh = heading_loss(accumulate(A["H"][:, 1], y[..., L.DH_IN_GLO:L.DH_IN_GLO + 3]), H)
        lf = fk_loss(y, L.J_LO)
        return nmse(sub, y, torch.cat([F["glo"][:, 1:], F["zn"][:, 1:]], -1)) + W_H * lh + W_FK * lf, dict(h=lh.item(), fk=lf.item())
    x = torch.cat([F["up_in"][:, 1:], noise(F["gup"][:, :-1], slice(L.N_O, None))], -1)
    y, _, _ = sub(x)
    lf = fk_loss(y, L.J_UP)
    return nmse(sub, y, torch.cat([F["gup"][:, 1:], F["onext"][:, 1:]], -1)) + W_FK * lf, dict(fk=lf.item())


def pose_columns(n_joints):
    """Positions and 6D rotations of a joint-state layout [p (3J) | v (3J) | q6 (6J) | ...]: what the
    smoothness term acts on (velocities, contacts and z are left to their own losses: a second
    difference of a contact step or of a velocity at a foot strike is a spike the target has)."""
    return torch.tensor(list(range(3 * n_joints)) + list(range(6 * n_joints, 12 * n_joints)))


IDX_LO, IDX_UP = pose_columns(len(L.J_LO)), pose_columns(len(L.J_UP))


def acc_loss(sub, y, target, idx):
    """Smoothness: MSE of the normalised outputs' second differences against the targets' (matching the
    motion's own accelerations, so it damps frame-to-frame noise without pulling towards stillness)."""
    d2 = lambda x: x[:, 2:, idx] - 2 * x[:, 1:-1, idx] + x[:, :-2, idx]
    return (((d2(y) - d2(target)) / sub.out_std[idx]) ** 2).mean()


TOES = [L.NAMES.index("Toes_L"), L.NAMES.index("Toes_R")]


def skate_loss(h, glo, gup, contact):
    """Foot skating: mean squared horizontal world speed (m/s) of each toe between consecutive frames on
    which the ground truth has that foot in contact (contact [B, T, 2]): the rollout's world pose, as the
    pipeline shows it (FK of the predicted rotations from the predicted hips and heading)."""
    P, _ = world_pose(h, glo, gup)
    v = (P[:, 1:, TOES][..., [0, 2]] - P[:, :-1, TOES][..., [0, 2]]) * L.FPS
    m = (contact[:, 1:] > 0.5) & (contact[:, :-1] > 0.5)
    return ((v ** 2).sum(-1) * m).sum() / m.sum().clamp(min=1)


def finetune_step(nets, A, T, hmd_frac=0.25, w_acc=0.0, w_skate=0.0):
    """One autoregressive rollout of T frames from ground-truth states; L = L_sig + L_lo + L_up
    (+ w_acc times the smoothness terms of G_lo's and G_up's joint positions and rotations, + w_skate times
    the foot-skating term, each when its weight is > 0)."""
    sig, lo, up = nets
    F0 = targets(A[:, :] if False else {k: v[:, 0:3] for k, v in A.items()}, A["H"][:, 0:3])
    h0, glo0, gup0 = A["H"][:, 1], F0["glo"][:, 0], F0["gup"][:, 0]
    o0 = F0["onext"][:, 0]  # frame 2 in frame h^1: stands in for missing controllers at the first step
    TP, TQ6 = A["TP"][:, 2:T + 2], A["TQ6"][:, 2:T + 2]
    B = TP.shape[0]
    valid = torch.ones(B, T, 3, dtype=torch.bool)
    valid[: int(B * hmd_frac), :, 1:] = False
    out, _, _ = rollout(nets, TP, TQ6, h0, glo0, gup0, o0, valid)
    h = out["h"]
    H = A["H"][:, 2:T + 2]
    # targets in the predicted heading frames (joint states, o*) and ground truth z / dh
    Hall = torch.cat([A["H"][:, 1:2], h, A["H"][:, T + 2:T + 3]], 1)
    G = {k: v[:, 1:T + 1] for k, v in A.items()}
    Fp = targets({k: A[k][:, 1:T + 3] for k in A}, Hall)
    Fg = targets({k: A[k][:, 1:T + 3] for k in A}, A["H"][:, 1:T + 3])
    lh = heading_loss(h, H)
    l_sig = nmse(sig, out["z"], Fg["z"]) + W_H * lh
    glo_t = torch.cat([Fp["glo"][..., :L.Z_IN_GLO], Fg["glo"][..., L.Z_IN_GLO:]], -1)
    l_lo = nmse(lo, out["glo"], glo_t, slice(0, L.N_GLO)) + W_H * lh + W_FK * fk_loss(out["glo"], L.J_LO)
    l_up = nmse(up, out["gup"], Fp["gup"], slice(0, L.N_GUP)) + nmse(up, out["ostar"], Fp["onext"], slice(L.N_GUP, None)) \
        + W_FK * fk_loss(out["gup"], L.J_UP)
    del G
    parts = dict(h=lh.item(), sig=l_sig.item(), lo=l_lo.item(), up=l_up.item())
    total = l_sig + l_lo + l_up
    if w_acc > 0:
        la = acc_loss(lo, out["glo"], glo_t, IDX_LO) + acc_loss(up, out["gup"], Fp["gup"], IDX_UP)
        parts["acc"] = la.item()
        total = total + w_acc * la
    if w_skate > 0:
        ls = skate_loss(h, out["glo"], out["gup"], A["CT"][:, 2:T + 2])
        parts["skate"] = ls.item()
        total = total + w_skate * ls
    return total, parts


def save(path, nets, info):
    torch.save({"nets": {s.name: s.state_dict() for s in nets}, "hidden": {s.name: s.hidden for s in nets},
                "info": info}, path)


def load(path):
    ck = torch.load(path, map_location="cpu")
    nets = [Sub(n, ck["hidden"][n]) for n in ("sig", "lo", "up")]
    for s in nets:
        s.load_state_dict(ck["nets"][s.name])
        s.eval()
    return nets, ck["info"]


def average(checkpoints, out):
    """Weight averaging of one run's snapshots (Izmailov et al. 2018, SWA): the mean of every float tensor.
    Snapshots of one fine-tuning run stay in one basin, and their mean smooths the SGD noise that makes
    any single snapshot's pipeline figures jump (README: the shipped weights)."""
    cks = [torch.load(c, map_location="cpu") for c in checkpoints]
    avg = cks[-1]
    for name, sd in avg["nets"].items():
        for k, v in sd.items():
            if v.is_floating_point():
                sd[k] = sum(c["nets"][name][k] for c in cks) / len(cks)
    avg["info"]["averaged"] = list(checkpoints)
    torch.save(avg, out)
    return f"wrote {out}: the mean of {len(cks)} checkpoints"


def val_loss(fn, data, seed=123, n=4):
    rng = np.random.default_rng(seed)
    torch.manual_seed(seed)
    with torch.no_grad():
        return float(np.mean([fn(rng).item() for _ in range(n)]))


def main(argv=None):
    p = argparse.ArgumentParser(prog="weights_tool.n3p train")
    p.add_argument("--train", required=True)
    p.add_argument("--val", required=True)
    p.add_argument("--out", required=True, help="checkpoint (.pt); stage checkpoints next to it")
    p.add_argument("--minutes", type=float, nargs=4, default=[5, 9, 9, 16],
                   help="wall-clock budget of the stages: sig, lo, up pretraining, fine-tuning")
    p.add_argument("--T", type=int, default=60)
    p.add_argument("--batch", type=int, default=32)
    p.add_argument("--lr", type=float, default=5e-4)
    p.add_argument("--hidden", type=int, nargs=3, default=[64, 128, 128])
    p.add_argument("--max-iters", type=int, default=10 ** 9)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--resume", default=None, help="checkpoint to continue from: pretraining is skipped, only "
                   "fine-tuning runs (its --minutes budget)")
    p.add_argument("--init", default=None, help="exported weights prefix (e.g. examples/weights/n3p) to start "
                   "every stage from, keeping its normalization: fine-tuning on new data")
    p.add_argument("--finetune-up", action="store_true", help="fine-tune G_up too (the paper freezes it): "
                   "lets the upper body adapt to device-realistic input")
    p.add_argument("--w-acc", type=float, default=0.0, help="weight of the smoothness term in fine-tuning "
                   "(second differences of the joint positions and rotations against the targets'); 0 = the paper's loss")
    p.add_argument("--w-skate", type=float, default=0.0, help="weight of the foot-skating term in fine-tuning "
                   "(squared world toe speed, m/s, while the ground truth's foot is in contact)")
    p.add_argument("--val-every", type=int, default=200)
    a = p.parse_args(argv)
    torch.set_num_threads(a.threads)
    torch.manual_seed(a.seed)
    rng = np.random.default_rng(a.seed)
    tr, va = Data(a.train), Data(a.val)
    cmd = "weights_tool.n3p train " + " ".join(argv if argv is not None else sys.argv[1:])
    if a.resume:
        nets, info = load(a.resume)
        info.setdefault("resumed", []).append(cmd)
    else:
        if a.init:
            from .weights import load as load_exported
            nets, _ = load_exported(a.init)
            print(f"init from {a.init}", flush=True)
        else:
            nets = [Sub(n, h) for n, h in zip(("sig", "lo", "up"), a.hidden)]
            set_normalization(nets, tr, rng)
        info = {"command": cmd, "T": a.T, "batch": a.batch, "lr": a.lr,
                "train_clips": int(len(tr.lens)), "train_frames": int(tr.lens.sum()), "stages": {},
                "init": a.init}
    print(f"train: {len(tr.lens)} clips {tr.lens.sum()} frames; val: {len(va.lens)} clips", flush=True)
    T = a.T
    for si, sub in enumerate(nets if not a.resume else []):
        opt = torch.optim.Adam(sub.parameters(), lr=a.lr)
        sub.train()
        t0, it = time.time(), 0
        while time.time() - t0 < a.minutes[si] * 60 and it < a.max_iters:
            loss, parts = pretrain_step(sub, batch(tr, rng, a.batch, T + 3), T)
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(sub.parameters(), 1.0)
            opt.step()
            it += 1
            if it % 100 == 0:
                print(f"[{sub.name}] it {it} {time.time() - t0:.0f}s loss {loss.item():.4f} {parts}", flush=True)
        sub.eval()
        vl = val_loss(lambda r: pretrain_step(sub, batch(va, r, 64, T + 3), T)[0], va)
        info["stages"][sub.name] = {"iterations": it, "val_loss": vl}
        print(f"[{sub.name}] done: {it} it, val loss {vl:.4f}", flush=True)
        save(a.out + f".{sub.name}", nets, info)
    # joint fine-tuning of G_sig + G_lo, G_up frozen (or trained too: --finetune-up)
    sig, lo, up = nets
    trained = [sig, lo] + ([up] if a.finetune_up else [])
    for prm in up.parameters():
        prm.requires_grad_(a.finetune_up)
    up.eval()
    params = [prm for s in trained for prm in s.parameters()]
    opt = torch.optim.Adam(params, lr=a.lr)
    t0, it, best = time.time(), 0, float("inf")
    ft = lambda r: finetune_step(nets, batch(va, r, 64, T + 3), T, w_acc=a.w_acc, w_skate=a.w_skate)[0]
    info["finetune"] = {"up": a.finetune_up, "w_acc": a.w_acc, "w_skate": a.w_skate}
    for s in trained:
        s.eval()
    best = val_loss(ft, va)
    print(f"[finetune] start val loss {best:.4f}", flush=True)
    save(a.out, nets, info)
    while time.time() - t0 < a.minutes[3] * 60 and it < a.max_iters:
        for s in trained:
            s.train()
        loss, parts = finetune_step(nets, batch(tr, rng, a.batch, T + 3), T, w_acc=a.w_acc, w_skate=a.w_skate)
        opt.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(params, 1.0)
        opt.step()
        it += 1
        if it % 25 == 0:
            print(f"[finetune] it {it} {time.time() - t0:.0f}s loss {loss.item():.4f} {parts}", flush=True)
        if it % a.val_every == 0:
            for s in trained:
                s.eval()
            vl = val_loss(ft, va)
            tag = ""
            if vl < best:
                best, tag = vl, " (best, saved)"
                info["stages"]["finetune"] = {"iterations": it, "val_loss": vl}
                save(a.out, nets, info)
            save(a.out + f".it{it}", nets, info)  # every snapshot: the pipeline, not this loss, picks
            print(f"[finetune] VAL it {it} {vl:.4f}{tag}", flush=True)
    for s in trained:
        s.eval()
    vl = val_loss(ft, va)
    if vl < best:
        info["stages"]["finetune"] = {"iterations": it, "val_loss": vl}
        save(a.out, nets, info)
    print(f"done: fine-tuning {it} it, best val {min(best, vl):.4f}", flush=True)


if __name__ == "__main__":
    main()
