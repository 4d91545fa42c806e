"""Fixtures of the napari plug-in's tests: the volvis package of this
build (PYTHONPATH from CTest, else build/<preset>/python), the CLI, the
real volumes of ../shared/data, and a .vvb made from one by volvis convert."""
import os
import pathlib
import subprocess
import sys

import pytest

# the Python tests' build_tree (tests/python): where this build's package and CLI are
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python"))
from build_tree import ROOT, cli, use_build_package  # noqa: E402

DATA = ROOT / ".." / "shared" / "data" / "volumes"
use_build_package("napari")


@pytest.fixture(scope="session")
def out_dir():
    d = pathlib.Path(os.environ.get("VV_TEST_OUT", ROOT / "build" / "test-out" / "napari"))
    d.mkdir(parents=True, exist_ok=True)
    return d


@pytest.fixture(scope="session")
def ct_vvb(out_dir):
    """The CT head (../shared/data, 256x256x108 i16) as a .vvb with 3 levels."""
    src = DATA / "ct_head.nrrd"
    if not src.exists():
        pytest.skip("%s is missing" % src)
    out = out_dir / "ct_head.vvb"
    subprocess.run([cli(), "convert", "-q", str(src), str(out)], check=True)
    return out


@pytest.fixture(scope="session")
def plugin():
    """The plug-in's manifest registered with npe2 in this process (the
    package is on PYTHONPATH, not installed: no entry point to find)."""
    import npe2
    from volvis.napari import MANIFEST
    pm = npe2.PluginManager.instance()
    if "volvis" not in pm._manifests:
        pm.register(npe2.PluginManifest.from_file(MANIFEST))
    return pm
