"""The C++ pipelines from Python: finds the `sparsebody` module (pybind11, weights_tool/native) and
runs a clip the way sparsebody_demo does, so evaluations need no demo subprocess.

  sb = pymod.load()                    # the module, or None when it is not built
  run = pymod.run_clip(sb, "clip.bvh", "lobstr")          # the demo's defaults
  run.out["position"]                  # [T, J, 3] world, user's size, one row per input frame
  run.shown()                          # the rows the demo writes to its BVH (a model step and an output)

The module is looked for on sys.path, then in $SPARSEBODY_PYMOD_DIR, then in build/python of this
checkout (cmake --build build --target sparsebody_python).
"""
import os
import sys
from dataclasses import dataclass, field

import numpy as np

from .lobstr.bvh import fk
from .lobstr.rotations import quat_to_matrix

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
MODELS = ("lobstr", "n3p", "n3p_physics")


def load(required=False):
    """The `sparsebody` extension module, or None (required: ImportError saying how to build it)."""
    dirs = [None, os.environ.get("SPARSEBODY_PYMOD_DIR"), os.path.join(ROOT, "build", "python")]
    for d in dirs:
        if d is not None:
            if not os.path.isdir(d):
                continue
            if d not in sys.path:
                sys.path.insert(0, d)
        try:
            import sparsebody
        except ImportError:
            continue
        if hasattr(sparsebody, "create"):  # not some namespace package of that name
            return sparsebody
        sys.modules.pop("sparsebody", None)
    if required:
        raise ImportError("the sparsebody Python module is not built: cmake -S . -B build && "
                          "cmake --build build --target sparsebody_python (needs pybind11-dev, python3-dev), "
                          "or set SPARSEBODY_PYMOD_DIR")
    return None


@dataclass
class Run:
    """One clip through one pipeline: the pipeline, its input (read_input's dict) and run() output."""
    pipe: object
    inp: dict
    out: dict
    extra: dict = field(default_factory=dict)

    def shown(self):
        """Indices of the rows the demo writes to its output BVH (steps > 0 and an output)."""
        return np.flatnonzero((self.out["steps"] > 0) & self.out["has_output"])

    def bvh_positions(self):
        """World positions [n, J, 3] (m) of the shown rows as the demo's output BVH holds them: each
        row's local rotations and root (at its user size) on the skeleton the run ended with (its
        proportions, at its final size: one skeleton per file). Equal to out["position"] wherever
        neither the calibration nor the body proportions changed during the run."""
        i = self.shown()
        R = quat_to_matrix(self.out["rotation"][i])                   # [n, J, 3, 3], row 0 the root's world
        t = np.broadcast_to(np.asarray(self.pipe.offsets) * self.out["user_scale"][-1], R.shape[:-1]).copy()
        par = list(self.pipe.parents)
        t[:, par.index(-1)] = self.out["root"][i] * self.out["user_scale"][i][:, None]
        return fk(par, R, t)[1]


def demo_options(extra):
    """Keyword arguments of run_clip from the demo's command-line options (offdist's `-- ...`); a
    ValueError for an option the module path does not reproduce."""
    kw, i = {}, 0
    while i < len(extra):
        a = extra[i]
        if a == "--storage":
            kw["storage"] = extra[i + 1]
            i += 1
        elif a == "--weights":
            kw["weights"] = extra[i + 1]
            i += 1
        elif a == "--mode":
            kw["mode"] = extra[i + 1]
            i += 1
        elif a == "--no-contact-ik":
            kw["contact_ik"] = False
        elif a == "--physics":
            kw["physics"] = True
        elif a == "--correction":
            kw["correction"] = extra[i + 1]
            i += 1
        elif a == "--foot-pin":
            kw["foot_pin"] = extra[i + 1]
            i += 1
        elif a == "--no-pelvis":
            kw["no_pelvis"] = True
        elif a == "--devices":
            kw["devices"] = True
        elif a == "--devices-stand":
            kw["devices_stand"] = float(extra[i + 1])
            i += 1
        elif a == "--device-seed":
            kw["device_seed"] = int(extra[i + 1])
            i += 1
        elif a == "--model":
            kw["model"] = {"neural3points": "n3p"}.get(extra[i + 1], extra[i + 1])
            i += 1
        elif a == "--quiet":
            pass
        else:
            raise ValueError(f"demo option {a} has no module equivalent")
        i += 1
    return kw


def run_clip(sb, path, model="lobstr", devices=False, device_seed=0, devices_stand=-1.0, no_pelvis=False,
             storage="auto", weights="", contact_ik=True, mode="streaming", physics=False, trackers_out="",
             chunk=0, controller_swap=True, correction="", foot_pin="toe"):
    """sparsebody_demo INPUT --model MODEL [...] without the subprocess: the same input synthesis
    (read_input), the same sizing (trackers at the joints: leg length; otherwise the automatic
    calibration), the same frame loop. physics (or model "n3p_physics"): Neural3Points' normal mode,
    correction: its learned PD-target correction (an n3p_correction_policy file). foot_pin: what
    Neural3Points direct mode pins, "toe" (default) or "ankle" (the demo's --foot-pin).
    chunk > 0 feeds the frames in batches of that many (the result is the same). Raises ValueError
    where the demo exits with an error (LoBSTr without a pelvis tracker)."""
    if physics and model == "lobstr":
        raise ValueError("--physics is Neural3Points' normal mode (use model n3p)")
    if physics:
        model = "n3p_physics"
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    inp = sb.read_input(path, devices=devices, device_seed=device_seed, devices_stand=devices_stand,
                        no_pelvis=no_pelvis, trackers_out=trackers_out)
    if model == "lobstr" and not inp["pelvis"]:
        raise ValueError(f"{path} has no valid pelvis tracker frame; LoBSTr needs one (use model n3p)")
    pipe = sb.create(model, weights=weights, storage=storage, contact_ik=contact_ik, mode=mode, controller_swap=controller_swap,
                     correction=correction, foot_pin=foot_pin)
    if inp["at_joints"]:
        L = inp["lengths"]
        pipe.fit_leg_length(inp["leg"], L["torso"], L["arm"])
    T = len(inp["time"])
    step = chunk if chunk > 0 else max(T, 1)
    parts = [pipe.run(inp["time"][a:a + step], inp["position"][a:a + step], inp["orientation"][a:a + step],
                      inp["valid"][a:a + step]) for a in range(0, T, step)]
    out = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]} if parts else {}
    return Run(pipe, inp, out)


def truth_rows(run):
    """Clip frame index of every row (the clip frame the row's pose shows, as demo_metrics: the
    shown time since the first input frame over the clip's frame time)."""
    t0 = run.inp["time"][0]
    ft = run.inp["clip_frame_time"]
    t = np.nan_to_num(run.out["time"] - t0, nan=0.0)
    return np.minimum(run.inp["clip_frames"] - 1, np.round(t / ft).astype(int))
