"""Evaluations through the sparsebody module: offdist gives the demo subprocess's figures in-process
(to the output BVH's print rounding), and weights_tool.plots writes real PNG figures."""
import os
import shutil
import struct

import numpy as np
import pytest

from weights_tool import offdist, plots, pymod
from weights_tool.tests.test_pymod import CLIP, demo, need_clip, sb  # noqa: F401 (fixtures)


@pytest.fixture(scope="module")
def clips(tmp_path_factory):
    """Two CMU clips in a folder (offdist takes a folder)."""
    need_clip()
    d = tmp_path_factory.mktemp("val")
    for f in (CLIP, "/usr/share/assimp/models/BVH/01_03.bvh"):
        if os.path.exists(f):
            shutil.copy(f, d)
    return str(d)


@pytest.mark.parametrize("model,mode", [("lobstr", "nominal"), ("n3p", "devices"), ("n3p", "csv")])
def test_offdist_same_figures_with_the_module_and_the_demo(sb, demo, clips, tmp_path, model, mode):  # noqa: F811
    a, fa = offdist.evaluate(demo, clips, mode, model, 1, [], str(tmp_path), sb=None)
    b, fb = offdist.evaluate(None, clips, mode, model, 1, [], str(tmp_path), sb=sb)
    assert not fa and not fb and a["clips"] == b["clips"] == 2 and a["frames"] == b["frames"] > 1000
    # The demo's BVH prints 6 significant digits (~1e-5 m per joint and frame): mean position errors
    # agree to ~1e-7 m; speeds, means of |a difference of positions|, keep the rounding noise
    # (0.017 cm/s at most on the validation clips).
    for k, tol in (("mpjpe", 2e-6), ("lower", 2e-6), ("toe", 2e-6), ("head", 2e-6), ("skate", 5e-4), ("still_feet", 5e-4)):
        assert abs(a[k] - b[k]) < tol or (np.isnan(a[k]) and np.isnan(b[k])), (k, a[k], b[k])  # NaN: no still frames
    assert a["mpjpe"] > 0.01  # a real error, not a comparison of nothing


def test_offdist_physics_runs_in_process(sb, clips, tmp_path):  # noqa: F811
    r, f = offdist.evaluate(None, clips, "nominal", "n3p", 1, ["--physics"], str(tmp_path), sb=sb)
    assert not f and r["clips"] == 2 and 0.01 < r["mpjpe"] < 0.5


def png_size(path):
    """(width, height) from the PNG header."""
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR"
    return struct.unpack(">II", head[16:24])


@pytest.mark.parametrize("model", ["lobstr", "n3p", "n3p_physics"])
def test_plots_are_written_and_not_empty(sb, tmp_path, model):  # noqa: F811
    need_clip()
    import matplotlib.image as mpimg
    files = plots.plot_clip(sb, CLIP, str(tmp_path), model, devices=True, device_seed=5, devices_stand=0.0)
    want = ["joint_error", "foot_height"] + (["residual"] if model == "n3p_physics" else [])
    assert len(files) == len(want)
    for f, w in zip(files, want):
        assert f.endswith(f"01_01_{model}_{w}.png") and os.path.getsize(f) > 20000
        assert png_size(f) in ((1200, 600), (1200, 500))
        img = mpimg.imread(f)[..., :3]
        # curves: many distinct colours, and most of the picture is not background
        assert len(np.unique((img * 255).astype(np.uint8).reshape(-1, 3), axis=0)) > 50
        assert (img.min(axis=-1) < 0.9).mean() > 0.02


def test_plots_command_line(sb, tmp_path):  # noqa: F811
    need_clip()
    assert plots.main([CLIP, "--model", "n3p", "--out", str(tmp_path)]) == 0
    assert sorted(os.listdir(tmp_path)) == ["01_01_n3p_foot_height.png", "01_01_n3p_joint_error.png"]
    t, e, out, tr = plots.clip_errors(pymod.run_clip(sb, CLIP, "n3p"))
    assert e.shape == (len(t), 12) and 0.005 < e.mean() < 0.3 and np.all(np.diff(t) > 0)


@pytest.mark.parametrize("opts", [["--model", "lobstr"], ["--model", "n3p", "--physics", "--devices", "--device-seed", "9"]],
                         ids=["lobstr", "n3p physics devices"])
def test_demo_metrics_equal_the_demos_printed_metrics(sb, demo, tmp_path, opts):  # noqa: F811
    """sparsebody.demo_metrics is the demo's Metrics on the same rows: its printout to 2 decimals."""
    import re
    import subprocess
    from weights_tool.lobstr import cpp_eval
    need_clip()
    r = subprocess.run([demo, CLIP, "-o", str(tmp_path / "o.bvh"), "--quiet"] + opts, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    printed = {}
    for line in r.stdout.splitlines():
        for label, k in cpp_eval.KEYS.items():
            if line.strip().startswith(label):
                v = re.findall(r"[-+]?\d+\.\d+", line)  # as cpp_eval parses it
                if v:
                    printed[k] = float(v[0])
    vals, frames = cpp_eval.module_metrics(sb, CLIP, opts)
    assert f"metrics vs the input clip ({frames} frames)" in r.stdout and frames > 500
    assert set(printed) == set(cpp_eval.KEYS.values()) - {"rot"}  # CMU skeleton: rotation error n/a
    for k, v in printed.items():
        assert abs(vals[k] - v) <= 0.005 + 1e-9, (k, vals[k], v)


def test_demo_metrics_of_a_z_up_clip_equal_the_y_up_originals(sb, tmp_path):  # noqa: F811
    """demo_metrics reads the clip as read_input does (recordings/clip_session.hpp): a Z-up copy of
    01_01 is turned to Y-up and gives the original's metrics (before, demo_metrics did not turn it)."""
    from weights_tool.lobstr import cpp_eval
    from weights_tool.tests.test_lobstr_pipeline import write_z_up
    need_clip()
    z_up = str(tmp_path / "01_01_z_up.bvh")
    write_z_up(CLIP, z_up)
    for opts in (["--model", "lobstr"], ["--model", "n3p", "--devices", "--device-seed", "3"]):
        a, fa = cpp_eval.module_metrics(sb, CLIP, opts)
        b, fb = cpp_eval.module_metrics(sb, z_up, opts)
        assert fa == fb > 500
        for k in a:
            assert abs(a[k] - b[k]) < 1e-3 or (np.isnan(a[k]) and np.isnan(b[k])), (opts, k, a[k], b[k])
        assert a["mpjpe"] > 1.0  # cm: a real error, not a comparison of nothing
