"""The example notebook runs top to bottom under jupyter nbconvert --execute,
and the script of the README's CLI examples runs and writes its outputs."""
import json
import os
import shutil
import subprocess
import sys


from conftest import ROOT

import volvis


def env():
    e = dict(os.environ)
    e["PYTHONPATH"] = os.path.dirname(os.path.dirname(volvis.__file__))
    e["VOLVIS_ROOT"] = str(ROOT)
    e["VOLVIS_WIDGETS"] = "0"  # nbclient cannot open Debian's ipywidgets 6 widgets
    e.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")
    return e


def test_notebook_executes(tmp_path):
    exe = shutil.which("jupyter-nbconvert") or shutil.which("jupyter")
    assert exe, "jupyter-nbconvert (Debian's jupyter-nbconvert) is not installed"
    cmd = [exe] if exe.endswith("nbconvert") else [exe, "nbconvert"]
    nb = ROOT / "examples" / "python" / "volvis_tour.ipynb"
    subprocess.run(cmd + ["--to", "notebook", "--execute", str(nb), "--output-dir",
                          str(tmp_path), "--ExecutePreprocessor.timeout=600"],
                   check=True, env=env(), cwd=nb.parent)
    out = json.loads((tmp_path / "volvis_tour.ipynb").read_text())
    cells = [c for c in out["cells"] if c["cell_type"] == "code"]
    assert all(c.get("execution_count") for c in cells)
    assert not any(o.get("output_type") == "error" for c in cells for o in c["outputs"])
    pngs = [o for c in cells for o in c["outputs"] if "image/png" in o.get("data", {})]
    assert len(pngs) >= 4  # the renders display inline (_repr_png_)


def test_readme_examples_script(tmp_path):
    subprocess.run([sys.executable, str(ROOT / "examples" / "python" / "readme_cli.py"),
                    str(tmp_path), "--frames", "3", "--size", "96"],
                   check=True, env=env(), cwd=ROOT)
    for name in ("head.png", "mip.png", "bone.png", "scene.png", "nut.nrrd", "head.vvc",
                 "fourier.png", "bone.ply", "smooth.nrrd", "labels.png", "nut_bolt.nrrd"):
        assert (tmp_path / name).stat().st_size > 0, name
    if volvis._lib_c.vv_video_codec_available(volvis._lib_c.VV_VIDEO_H264):
        assert (tmp_path / "head.mp4").stat().st_size > 0
