"""Where the Python tests find this build (tests/python/conftest.py and
tests/napari/conftest.py share it): the volvis package on sys.path and the
volvis CLI, from CTest's environment or else the tree's build/<preset>."""
import os
import pathlib
import shutil
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
PRESETS = ("release", "asan", "debug")


def use_build_package(sub=""):
    """Unless a folder on sys.path already holds the package volvis (with its
    subpackage @sub: PYTHONPATH from CTest, or an installed wheel), puts the
    first build/<preset>/python that holds it first on sys.path."""
    want = pathlib.Path("volvis", sub)
    if any(pathlib.Path(p, want).exists() for p in sys.path if p):
        return
    for preset in PRESETS:
        cand = ROOT / "build" / preset / "python"
        if (cand / want).exists():
            sys.path.insert(0, str(cand))
            return


def cli():
    """The volvis CLI of this build (VV_CLI from CTest, else the tree's, else PATH's)."""
    env = os.environ.get("VV_CLI")
    if env and os.path.exists(env):
        return env
    for preset in PRESETS:
        p = ROOT / "build" / preset / "volvis"
        if p.exists():
            return str(p)
    return shutil.which("volvis")
