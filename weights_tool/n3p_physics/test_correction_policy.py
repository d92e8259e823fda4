"""The shipped Neural3Points correction policy (examples/weights/n3p_correction_policy.json, issue 14
item 4) through the run-time pipeline on every 10th validation clip (3-point input, the direct-mode
prediction as reference, residual wrench off): it falls less often than the model-based controller
alone and tracks no worse. Run by CTest as n3p_correction_policy_test (N3P_PHYSICS_EVAL: the
n3p_physics_eval binary); skipped without the validation data."""
import os
import re
import subprocess
import tarfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TAR = os.path.join(ROOT, "..", "shared", "data", "bandai-namco", "validation.tar.xz")
POLICY = os.path.join(ROOT, "examples", "weights", "n3p_correction_policy.json")


def figures(out):
    mpjpe = float(re.search(r"^physics +MPJPE +([0-9.]+) cm", out, re.M).group(1))
    falls = float(re.search(r"; ([0-9.]+) per minute of output", out).group(1))
    return falls, mpjpe


def test_shipped_correction_falls_less_than_the_model_based_controller(tmp_path):
    ev = os.environ.get("N3P_PHYSICS_EVAL") or os.path.join(ROOT, "build", "examples", "n3p_physics_eval")
    if not os.path.exists(TAR):
        pytest.skip(f"{TAR} not found")
    if not os.path.exists(ev):
        pytest.skip("n3p_physics_eval is not built")
    clips = tmp_path / "clips"
    with tarfile.open(TAR) as t:
        members = [m for m in t.getmembers() if m.isfile()]
        stems = sorted({os.path.splitext(os.path.basename(m.name))[0] for m in members})[::10]
        for m in members:
            if os.path.splitext(os.path.basename(m.name))[0] in stems:
                m.name = os.path.basename(m.name)
                t.extract(m, clips)
    from ..n3p import dataset, evaluate
    npz, dump = str(tmp_path / "val.npz"), str(tmp_path / "val_direct.json")
    dataset.build(str(clips), npz, 1, None, 0, True, 0)
    evaluate.dump_for_direct_mode(dataset.Data(npz), dump, None)
    off = ["--max-force", "0", "--max-torque", "0"]
    plain = subprocess.run([ev, dump] + off, capture_output=True, text=True, check=True).stdout
    corr = subprocess.run([ev, dump] + off + ["--correction", POLICY], capture_output=True, text=True, check=True).stdout
    (fp, ep), (fc, ec) = figures(plain), figures(corr)
    print(f"{len(stems)} clips: falls per minute {fp:.1f} -> {fc:.1f}, MPJPE {ep:.2f} -> {ec:.2f} cm")
    assert fc < 0.9 * fp
    assert ec < ep + 1.0
