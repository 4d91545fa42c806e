"""volvis.widgets.View in a notebook executed headless by nbclient
(test_python_widget_nbclient): a real kernel (ipykernel of .venv) imports
volvis.widgets, builds a View of the CT head, sets the camera and the mode,
and calls snapshot(). Checked: the widget cell's output is a widget view
(application/vnd.jupyter.widget-view+json) whose model nbclient recorded
as an anywidget model holding the traits set; the snapshot's shape, dtype
and SHA-256 equal those of volvis.render of the same World with the same
camera in this process.

Usage: widget_nbclient.py [BUILD_PYTHON_DIR OUT_DIR]. Exit 77 when nbclient,
nbformat, ipykernel or anywidget is missing."""
import hashlib
import json
import os
import sys
import tempfile
import time

import widget_setup
from widget_setup import HEAD

PYDIR, OUT, _ = widget_setup.start("widget_nbclient",
                                   ["anywidget", "ipykernel", "nbformat", "numpy", "nbclient"])
import nbformat  # noqa: E402
import numpy as np  # noqa: E402
from nbclient import NotebookClient  # noqa: E402

import volvis  # noqa: E402

EYE = [120.0, -420.0, 160.0]
CELLS = [
    "import json, numpy as np\n"
    "import volvis\n"
    "from volvis.widgets import View\n"
    "v = View(%r, size=(256, 192), preset='ct-bone')\n"
    "v" % str(HEAD),
    "v.eye = %r\n"
    "v.mode = 'mip'\n"
    "a = v.snapshot()\n"
    "import hashlib\n"
    "print(json.dumps({'shape': a.shape, 'dtype': str(a.dtype), 'mean': float(a.mean()),\n"
    "                  'sha256': hashlib.sha256(a.tobytes()).hexdigest(), 'eye': v.eye,\n"
    "                  'at': v.at, 'up': v.up, 'fov': v.fov}))" % (EYE,),
    "v.close()",
]

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


OUT.mkdir(parents=True, exist_ok=True)
t0 = time.monotonic()
nb = nbformat.v4.new_notebook()
nb.cells = [nbformat.v4.new_code_cell(c) for c in CELLS]
with tempfile.TemporaryDirectory(prefix="volvis-nbclient-") as tmp:
    env = {"PYTHONPATH": str(PYDIR), "JUPYTER_DATA_DIR": tmp + "/data",
           "JUPYTER_RUNTIME_DIR": tmp + "/runtime", "IPYTHONDIR": tmp + "/ipython",
           "MPLBACKEND": "agg"}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        client = NotebookClient(nb, timeout=120, kernel_name="python3",
                                resources={"metadata": {"path": tmp}}, store_widget_state=True)
        client.execute()
    finally:
        for k, val in old.items():
            if val is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = val
nbformat.write(nb, str(OUT / "widget.ipynb"))

outs = nb.cells[0].outputs
views = [o for o in outs if o.get("output_type") in ("execute_result", "display_data") and
         "application/vnd.jupyter.widget-view+json" in o.get("data", {})]
check(len(views) == 1, "the View cell shows a widget view")
state = nb.metadata.get("widgets", {}).get("application/vnd.jupyter.widget-state+json", {})
models = state.get("state", {})
if views:
    mid = views[0]["data"]["application/vnd.jupyter.widget-view+json"]["model_id"]
    m = models.get(mid, {})
    check(m.get("model_name") == "AnyModel" and m.get("model_module") == "anywidget",
          "its model is an anywidget model (%s %s)" % (m.get("model_module"), m.get("model_name")))
    st = m.get("state", {})
    check(st.get("mode") == "mip" and st.get("eye") == EYE and st.get("preset") == "ct-bone",
          "the recorded state holds the traits set in the notebook")
    check("_esm" in st and "msg:custom" in st.get("_esm", ""), "the model carries the page module")

text = "".join(o.get("text", "") for o in nb.cells[1].outputs if o.get("output_type") == "stream")
errs = [o for c in nb.cells for o in c.outputs if o.get("output_type") == "error"]
check(not errs, "no cell raised: %s" % [e.get("evalue") for e in errs])
try:
    got = json.loads(text.strip().splitlines()[-1])
except (ValueError, IndexError):
    got = {}
check(got.get("shape") == [192, 256, 4] and got.get("dtype") == "uint8",
      "snapshot(): %s %s" % (got.get("shape"), got.get("dtype")))

# the same World and camera rendered here
w = volvis.World.open(HEAD)
w.view.size = (256, 192)
o = w.objects[0]
o.tf = volvis.TransferFunction.preset("ct-bone", o.volume)
o.mode = "mip"
if got:
    w.view.eye, w.view.at, w.view.up, w.view.fov = got["eye"], got["at"], got["up"], got["fov"]
want = volvis.render(w, renderer="raycast")
check(got.get("eye") == EYE, "the kernel's camera is the one set")
check(got.get("sha256") == hashlib.sha256(np.asarray(want).tobytes()).hexdigest(),
      "the snapshot equals volvis.render of the same World here, bit for bit (mean %.2f vs %.2f)"
      % (got.get("mean", -1), float(np.asarray(want).mean())))
print("widget_nbclient: %.1f s, %d failures" % (time.monotonic() - t0, len(failures)))
sys.exit(1 if failures else 0)
