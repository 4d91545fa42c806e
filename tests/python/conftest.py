"""Shared fixtures of the Python package's tests (tests/python).

Run by CTest (test_python) with PYTHONPATH=build/<preset>/python; by hand:
PYTHONPATH=build/release/python /usr/bin/python3 -m pytest tests/python
"""
import os
import pathlib

import numpy as np
import pytest

from build_tree import ROOT, cli  # noqa: F401 (cli: the tests' import of it)
from build_tree import use_build_package

DATA = ROOT.parent / "shared" / "data"
if not DATA.exists():
    DATA = ROOT / ".." / "shared" / "data"

use_build_package()

import volvis  # noqa: E402

# test_python_wheel (tests/python/wheel.sh): the package must be the wheel
# installed in that environment, never a build tree's
if os.environ.get("VV_EXPECT_PREFIX"):
    _want = pathlib.Path(os.environ["VV_EXPECT_PREFIX"]).resolve()
    if _want not in pathlib.Path(volvis.__file__).resolve().parents:
        raise RuntimeError("volvis imported from %s, not from %s" % (volvis.__file__, _want))

SANITIZER = bool(os.environ.get("VV_SANITIZER"))


@pytest.fixture
def out_dir(tmp_path):
    return tmp_path


@pytest.fixture(scope="session")
def ct_head():
    return volvis.open(DATA / "volumes" / "ct_head.nrrd")


def data(*parts):
    return DATA.joinpath(*parts)


def read_png(path):
    return volvis.read_png(path)


@pytest.fixture
def rng():
    return np.random.default_rng(1234)
