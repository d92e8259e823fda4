"""Training with the paper's losses (§3.3):
  L = l1 L_pose + l2 L_FK + l3 L_velocity + l4/2 (L_contact^left + L_contact^right)
  L_pose     = |Y^pose - Yhat^pose|_1                 (mean over the 48 6D values)
  L_FK       = |FK(Yhat) - FK(Y)|_2                   (toe-base positions, hips frame, metres)
  L_velocity = |(FK(Yhat_i) - FK(Yhat_i-1)) - (FK(Y_i) - FK(Y_i-1))|_2
  L_contact  = cross-entropy of the per-foot contact logits
with l1 = 1, l2 = 0.1, l3 = 0.1, l4 = 1e-6 (the contact head only receives L_contact, and Adam is
invariant to a loss scale, so the small l4 keeps the latent shaped by the pose terms).
Adam, lr 1e-3 decayed by 0.999 every `decay_every` iterations; batches of random chunks picked with
probability proportional to clip length (Appendix 3). Chunks are longer than the 1 s window (loss on
every frame) so that streaming mode (state carried over the whole clip) is trained too.
CPU only; a wall-clock budget stops training and the best checkpoint by validation loss is kept.
"""
import argparse
import json
import time

import numpy as np
import torch
import torch.nn.functional as F

from ..nets import LoBSTrNet
from . import dataset
from .skeleton import LOWER
from .standard import STANDARD

LAMBDA = (1.0, 0.1, 0.1, 1e-6)


def rot6d_to_matrix(d):
    a, b = d[..., 0:3], d[..., 3:6]
    z = F.normalize(a, dim=-1)
    x = F.normalize(torch.cross(b, z, dim=-1), dim=-1)
    y = torch.cross(z, x, dim=-1)
    return torch.stack([x, y, z], dim=-1)


class ToeFK:
    """Toe-base positions in the hips frame from the 8 lower-body local rotations (standard skeleton)."""

    def __init__(self):
        off = {n: torch.tensor(STANDARD["offsets"][STANDARD["names"].index(n)], dtype=torch.float32) for n in LOWER}
        self.off = off

    def __call__(self, y6d):
        R = rot6d_to_matrix(y6d.reshape(*y6d.shape[:-1], 8, 6))
        out = []
        for s in (0, 4):
            ul, ll, ft, toe = (LOWER[s + i] for i in range(4))
            p = self.off[toe]
            p = self.off[ft] + torch.einsum("...ij,j->...i", R[..., s + 2, :, :], p)
            p = self.off[ll] + torch.einsum("...ij,...j->...i", R[..., s + 1, :, :], p)
            p = self.off[ul] + torch.einsum("...ij,...j->...i", R[..., s + 0, :, :], p)
            out.append(p)
        return torch.stack(out, dim=-2)  # [..., 2, 3]


def losses(out, Y, C, mask, fk):
    """Per-term losses (masked means) for network outputs `out` [B, T, 52] with contact logits."""
    m = mask.float()
    n = m.sum().clamp(min=1)
    pose = ((out[..., :48] - Y).abs().mean(-1) * m).sum() / n
    pf, pt = fk(out[..., :48]), fk(Y)
    fkl = ((pf - pt).norm(dim=-1).mean(-1) * m).sum() / n
    dv = (pf[:, 1:] - pf[:, :-1]) - (pt[:, 1:] - pt[:, :-1])
    mv = m[:, 1:] * m[:, :-1]
    vel = (dv.norm(dim=-1).mean(-1) * mv).sum() / mv.sum().clamp(min=1)
    logits = out[..., 48:].reshape(*out.shape[:2], 2, 2)
    ce = F.cross_entropy(logits.reshape(-1, 2), C.reshape(-1), reduction="none").reshape(*C.shape)
    ce = (ce.sum(-1) * m).sum() / n  # left + right
    total = LAMBDA[0] * pose + LAMBDA[1] * fkl + LAMBDA[2] * vel + LAMBDA[3] / 2 * ce
    return total, dict(pose=pose.item(), fk=fkl.item(), vel=vel.item(), ce=ce.item())


def padded(X, Y, C, lens, starts, idx, T=None, rng=None):
    """Batch of sequences (whole, or random chunks of T frames), zero padded with a mask."""
    L = T if T else int(lens[idx].max())
    B = len(idx)
    xb = np.zeros((B, L, X.shape[1]), np.float32)
    yb = np.zeros((B, L, 48), np.float32)
    cb = np.zeros((B, L, 2), np.int64)
    mb = np.zeros((B, L), bool)
    for b, i in enumerate(idx):
        n = int(lens[i])
        s = int(starts[i])
        if T and n > T:
            o = int(rng.integers(0, n - T + 1))
            s, n = s + o, T
        xb[b, :n], yb[b, :n], cb[b, :n], mb[b, :n] = X[s:s + n], Y[s:s + n], C[s:s + n], True
    return torch.from_numpy(xb), torch.from_numpy(yb), torch.from_numpy(cb), torch.from_numpy(mb)


def evaluate_loss(model, val, mean, std, fk, chunk=64):
    X, Y, C, lens, starts, _ = val
    model.eval()
    tot, agg, n = 0.0, {}, 0
    with torch.no_grad():
        order = np.argsort(lens)
        for i in range(0, len(order), chunk):
            idx = order[i:i + chunk]
            xb, yb, cb, mb = padded(X, Y, C, lens, starts, idx)
            out, _ = model((xb - mean) / std, logits=True)
            l, parts = losses(out, yb, cb, mb, fk)
            w = float(mb.sum())
            tot += l.item() * w
            for k, v in parts.items():
                agg[k] = agg.get(k, 0.0) + v * w
            n += w
    model.train()
    return tot / n, {k: v / n for k, v in agg.items()}


def main(argv=None):
    p = argparse.ArgumentParser(prog="weights_tool.lobstr train")
    p.add_argument("--train", required=True)
    p.add_argument("--val", required=True)
    p.add_argument("--out", required=True, help="checkpoint path (.pt), best by validation loss")
    p.add_argument("--hidden", type=int, default=256)
    p.add_argument("--latent", type=int, default=128)
    p.add_argument("--batch", type=int, default=128)
    p.add_argument("--chunk", type=int, default=64)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--decay-every", type=int, default=10)
    p.add_argument("--minutes", type=float, default=60.0)
    p.add_argument("--max-iters", type=int, default=10 ** 9)
    p.add_argument("--val-every", type=int, default=200)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--init", default=None, help="start from these weights (.pt checkpoint or exported "
                   ".weights.json) and keep their input normalization: fine-tuning")
    p.add_argument("--resume", default=None, help="continue a run from its OUT.last checkpoint (model, "
                   "optimizer, schedule, iteration, best loss); --minutes counts from the resume")
    a = p.parse_args(argv)
    torch.set_num_threads(a.threads)
    torch.manual_seed(a.seed)
    rng = np.random.default_rng(a.seed)
    tr, val = dataset.load(a.train), dataset.load(a.val)
    X, Y, C, lens, starts, _ = tr
    mean = X.mean(0)
    std = np.maximum(X.std(0), 1e-3)
    tmean, tstd = torch.from_numpy(mean), torch.from_numpy(std)
    model = LoBSTrNet(hidden=a.hidden, latent=a.latent)
    if a.init:
        sd, norm = load_init(a.init)
        model.load_state_dict(sd, strict=True)
        mean, std = norm["input_mean"].astype(np.float64), norm["input_std"].astype(np.float64)
        tmean, tstd = torch.from_numpy(mean).float(), torch.from_numpy(std).float()
        print(f"init from {a.init}", flush=True)
    opt = torch.optim.Adam(model.parameters(), lr=a.lr)
    sched = torch.optim.lr_scheduler.StepLR(opt, step_size=a.decay_every, gamma=0.999)
    fk = ToeFK()
    prob = lens / lens.sum()
    best, t0, it = float("inf"), time.time(), 0
    if a.resume:
        ck = torch.load(a.resume, weights_only=False)
        model.load_state_dict(ck["state_dict"])
        opt.load_state_dict(ck["optimizer"])
        sched.load_state_dict(ck["scheduler"])
        mean, std = ck["normalization"]["input_mean"].numpy().astype(np.float64), ck["normalization"]["input_std"].numpy().astype(np.float64)
        tmean, tstd = torch.from_numpy(mean).float(), torch.from_numpy(std).float()
        it, best = ck["iteration"], ck["best"]
        rng.bit_generator.state = ck["rng"]
        torch.set_rng_state(ck["torch_rng"])
        print(f"resumed {a.resume} at iteration {it}, best validation loss {best:.4f}", flush=True)
    print(f"train: {len(lens)} sequences, {lens.sum()} frames; val: {len(val[3])} sequences; "
          f"H={a.hidden} latent={a.latent}", flush=True)
    while it < a.max_iters and time.time() - t0 < a.minutes * 60:
        idx = rng.choice(len(lens), size=a.batch, p=prob)
        xb, yb, cb, mb = padded(X, Y, C, lens, starts, idx, a.chunk, rng)
        out, _ = model((xb - tmean) / tstd, logits=True)
        loss, parts = losses(out, yb, cb, mb, fk)
        opt.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()
        sched.step()
        it += 1
        if it % 50 == 0:
            print(f"it {it} {time.time() - t0:.0f}s loss {loss.item():.4f} " +
                  " ".join(f"{k} {v:.4f}" for k, v in parts.items()), flush=True)
        if it % a.val_every == 0:
            vl, vp = evaluate_loss(model, val, tmean, tstd, fk)
            tag = ""
            if vl < best:
                best, tag = vl, " (best, saved)"
                save(a.out, model, mean, std, a, it, vl)
            print(f"VAL it {it} loss {vl:.4f} " + " ".join(f"{k} {v:.4f}" for k, v in vp.items()) + tag, flush=True)
            save_last(a.out + ".last", model, opt, sched, mean, std, it, best, rng)
    vl, vp = evaluate_loss(model, val, tmean, tstd, fk)
    if vl < best:
        save(a.out, model, mean, std, a, it, vl)
        best = vl
    print(f"done: {it} iterations in {time.time() - t0:.0f}s, best validation loss {best:.4f}", flush=True)


def load_init(path):
    """(state_dict, normalization numpy) from a checkpoint or an exported weights JSON."""
    if path.endswith(".json"):
        from ..format import read_weights
        _, tensors, norm = read_weights(path)
        return {k: torch.from_numpy(v).float() for k, v in tensors.items()}, norm
    ck = torch.load(path, weights_only=False)
    return ck["state_dict"], {k: v.numpy() for k, v in ck["normalization"].items()}


def save_last(path, model, opt, sched, mean, std, it, best, rng):
    """Everything --resume needs (written next to the best checkpoint at every validation)."""
    torch.save({"state_dict": model.state_dict(), "optimizer": opt.state_dict(), "scheduler": sched.state_dict(),
                "normalization": {"input_mean": torch.from_numpy(mean.astype(np.float32)),
                                  "input_std": torch.from_numpy(std.astype(np.float32))},
                "iteration": it, "best": best, "rng": rng.bit_generator.state, "torch_rng": torch.get_rng_state()},
               path + ".tmp")
    import os
    os.replace(path + ".tmp", path)


def save(path, model, mean, std, a, it, vl):
    torch.save({"state_dict": model.state_dict(),
                "normalization": {"input_mean": torch.from_numpy(mean.astype(np.float32)),
                                  "input_std": torch.from_numpy(std.astype(np.float32))},
                "config": {"hidden": a.hidden, "latent": a.latent, "iterations": it, "val_loss": vl,
                           "batch": a.batch, "chunk": a.chunk, "lr": a.lr, "decay_every": a.decay_every,
                           "minutes": a.minutes, "seed": a.seed}}, path)


if __name__ == "__main__":
    main()
