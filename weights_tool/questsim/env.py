"""The batched C++ QuestSim training environment (include/sparsebody/training/questsim_env.hpp),
imported from the build tree like the `sparsebody` module (weights_tool/pymod.py): $SPARSEBODY_PYMOD_DIR,
else build*/python under the repository."""
import glob
import importlib
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def load_module():
    dirs = [os.environ["SPARSEBODY_PYMOD_DIR"]] if os.environ.get("SPARSEBODY_PYMOD_DIR") else []
    dirs += sorted(glob.glob(os.path.join(ROOT, "build*", "python")))
    for d in dirs:
        if glob.glob(os.path.join(d, "_questsim_env*.so")):
            if d not in sys.path:
                sys.path.insert(0, d)
            return importlib.import_module("_questsim_env")
    raise ImportError("_questsim_env not built: cmake --build build --target _questsim_env "
                      "(needs pybind11-dev and python3-dev), or set SPARSEBODY_PYMOD_DIR")
