#!/usr/bin/env python3
"""Runs the napari plug-in's tests (tests/napari) for CTest (test_napari_plugin):
napari, pytest-qt and the volvis package of this build, under Xvfb (the
caller, xvfb-run). Exit 77 (skipped) when napari, pytest-qt or the package
is missing, or when any test was skipped; pytest's status when one failed."""
import os
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
missing = []
for mod in ("pytest", "pytestqt", "napari", "npe2"):
    try:
        __import__(mod)
    except ImportError:
        missing.append(mod)
if missing:
    print("test_napari_plugin: skipped: %s not installed in %s (bash scripts/install-deps.sh "
          "test makes .venv)" % (", ".join(missing), sys.executable))
    sys.exit(77)
if not os.environ.get("DISPLAY") and os.environ.get("QT_QPA_PLATFORM") != "offscreen":
    print("test_napari_plugin: skipped: no X display (run under xvfb-run)")
    sys.exit(77)
sys.path.insert(0, str(ROOT / "tests" / "python"))
import run_pytest  # noqa: E402

sys.argv = [sys.argv[0], str(pathlib.Path(__file__).parent)] + sys.argv[1:]
sys.exit(run_pytest.main())
