"""PNG figures of one clip through a C++ pipeline (via the sparsebody Python module):

  <clip>_<model>_joint_error.png   per-joint position error over time (the 12 role joints, cm)
  <clip>_<model>_foot_height.png   toe height of the output and the clip, predicted contacts shaded
  <clip>_<model>_residual.png      physics only: residual root wrench per frame (force N, torque N m)

  /usr/bin/python3 -m weights_tool.plots CLIP.bvh --model lobstr|n3p|n3p_physics --out DIR \\
        [--devices] [--device-seed S] [--devices-stand T] [--storage auto|float|f16|q8] [--no-contact-ik]

Inputs and rows are the demo's (pymod.run_clip); the error is the pipeline's own output at the
user's size against the clip frame each row shows (the physics output is 0.1 s behind its input).
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import pymod  # noqa: E402

ROLES = ["hips", "head", "hand_l", "hand_r", "upleg_l", "upleg_r", "leg_l", "leg_r", "foot_l", "foot_r",
         "toe_l", "toe_r"]  # offdist.ROLES


def clip_errors(run):
    """(seconds [n], error [n, 12] m, output [n, 12, 3], truth [n, 12, 3]) of the rows that show a pose."""
    rows = run.shown()
    g = pymod.truth_rows(run)[rows]
    out = run.out["position"][rows][:, [run.pipe.roles[k] for k in ROLES]]
    tr = run.inp["truth_position"][g][:, [run.inp["truth_roles"][k] for k in ROLES]]
    t = run.out["time"][rows] - run.inp["time"][0]
    return t, np.linalg.norm(out - tr, axis=-1), out, tr


def _spans(mask):
    """(start, end) index pairs of the runs of True in mask."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    d = np.flatnonzero(np.diff(m.astype(int)))
    return list(zip(d[::2], d[1::2]))


def plot_clip(sb, path, out_dir, model="lobstr", dpi=100, **run_kwargs):
    """Writes the figures of one clip; returns their paths."""
    run = pymod.run_clip(sb, path, model, **run_kwargs)
    model = run.pipe.model
    os.makedirs(out_dir, exist_ok=True)
    stem = os.path.join(out_dir, f"{os.path.splitext(os.path.basename(path))[0]}_{model}")
    t, e, out, tr = clip_errors(run)
    title = f"{os.path.basename(path)}: {run.pipe.description.split(',')[0]}"
    written = []

    fig, ax = plt.subplots(figsize=(12, 6))
    for k, name in enumerate(ROLES):
        ax.plot(t, 100 * e[:, k], lw=1.0, label=name, color=plt.cm.tab20(k / len(ROLES)))
    ax.set_xlabel("clip time (s)")
    ax.set_ylabel("position error (cm)")
    ax.set_title(f"{title}: per-joint error, MPJPE {100 * e.mean():.2f} cm over {len(t)} frames")
    ax.legend(ncol=6, fontsize=8, loc="upper right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    written.append(stem + "_joint_error.png")
    fig.savefig(written[-1], dpi=dpi)
    plt.close(fig)

    rows = run.shown()
    contact = run.out["contact"][rows]
    fig, axes = plt.subplots(2, 1, figsize=(12, 6), sharex=True)
    for s, (ax, name) in enumerate(zip(axes, ("toe_l", "toe_r"))):
        k = ROLES.index(name)
        for a, b in _spans(contact[:, s]):
            ax.axvspan(t[a], t[min(b, len(t) - 1)], color="tab:green", alpha=0.2, lw=0)
        ax.plot(t, 100 * out[:, k, 1], color="tab:blue", lw=1.2, label=f"{name} output")
        ax.plot(t, 100 * tr[:, k, 1], color="black", lw=1.0, ls="--", label=f"{name} clip")
        ax.set_ylabel("height (cm)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8, title="shaded: predicted contact" if s == 0 else None)
    axes[-1].set_xlabel("clip time (s)")
    axes[0].set_title(f"{title}: toe height, contacts ({'simulated' if run.pipe.physics else 'predicted'})")
    fig.tight_layout()
    written.append(stem + "_foot_height.png")
    fig.savefig(written[-1], dpi=dpi)
    plt.close(fig)

    if run.pipe.physics:
        f, tq = run.out["residual_force"][rows], run.out["residual_torque"][rows]
        fig, ax = plt.subplots(figsize=(12, 5))
        ax.plot(t, f, color="tab:red", lw=1.0, label="force (N)")
        ax.set_xlabel("clip time of the simulated pose (s)")
        ax.set_ylabel("residual force (N)", color="tab:red")
        ax2 = ax.twinx()
        ax2.plot(t, tq, color="tab:purple", lw=1.0, label="torque (N m)")
        ax2.set_ylabel("residual torque (N m)", color="tab:purple")
        falls = np.flatnonzero(np.diff(run.out["falls"][rows], prepend=run.out["falls"][rows][:1]) > 0)
        for i in falls:
            ax.axvline(t[i], color="black", ls=":", lw=1)
        sm = run.pipe.summary()
        ax.set_title(f"{title}: residual root wrench per frame (mean {sm['residual_force_mean']:.1f} N / "
                     f"{sm['residual_torque_mean']:.1f} N m, {sm['falls']} falls)")
        ax.grid(alpha=0.3)
        fig.tight_layout()
        written.append(stem + "_residual.png")
        fig.savefig(written[-1], dpi=dpi)
        plt.close(fig)
    return written


def main(argv=None):
    p = argparse.ArgumentParser(prog="weights_tool.plots", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("clip", help="a BVH clip (trackers synthesised as the demo does) or a tracker CSV with no truth")
    p.add_argument("--model", choices=pymod.MODELS, default="lobstr")
    p.add_argument("--out", required=True)
    p.add_argument("--devices", action="store_true")
    p.add_argument("--device-seed", type=int, default=0)
    p.add_argument("--devices-stand", type=float, default=-1.0)
    p.add_argument("--storage", default="auto")
    p.add_argument("--no-contact-ik", action="store_true")
    a = p.parse_args(argv)
    if not a.clip.lower().endswith(".bvh"):
        p.error("the figures compare with the clip: give a BVH")
    sb = pymod.load(required=True)
    for f in plot_clip(sb, a.clip, a.out, a.model, devices=a.devices, device_seed=a.device_seed,
                       devices_stand=a.devices_stand, storage=a.storage, contact_ik=not a.no_contact_ik):
        print(f"wrote   {f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
