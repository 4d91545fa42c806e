"""volvis.widgets.View in a real JupyterLab 4 or Jupyter Notebook 7 driven by
Debian's Chromium (test_python_widget_jupyterlab, test_python_widget_notebook7):
the test starts `jupyter lab` (or `jupyter notebook`) of .venv on a free port
with a token, a temporary root folder and its own Jupyter folders, opens a
notebook in headless Chromium (selenium with Debian's chromedriver) at
/lab/tree/NAME.ipynb (or Notebook 7's /notebooks/NAME.ipynb), checks that the
page is the front end asked for (its #jupyter-config-data: appName,
appVersion, notebookPage), runs the View cell, waits for the widget's first
full frame, drags on it with the mouse (ActionChains), and checks that the
canvas shows a different image, that the frames while dragging were
reduced ones, that a full frame follows the drag, and that the camera the
next cell prints (the Python side's eye trait) moved at the same distance
from the look-at point; then the wheel and a two-finger touch pinch (WebDriver touch
pointers) and the + key must zoom by 1.1^3 (300 px of wheel) times 3 (the
fingers' final over first distance) times 1.1; the mode and preset menus
and the axial slice slider must set their traits. Both front ends are
JupyterLab's notebook components (the same .jp-Notebook, .jp-Cell and
.jp-OutputArea-output elements and the toolbar's execution indicator), so
one script drives both; what differs is in FRONTS. Screenshots of the
notebook go to OUT_DIR (FRONT_before.png, FRONT_after.png,
FRONT_zoomed.png, FRONT_failed.png on a failure). The server and the
browser are stopped whatever happens.

Usage: widget_jupyterlab.py [BUILD_PYTHON_DIR OUT_DIR [lab|notebook]] (default
lab). Exit 77 when jupyterlab (lab), notebook 7 (notebook), selenium,
anywidget, chromium or chromedriver is missing."""
import base64
import json
import os
import pathlib
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

import widget_setup
from widget_setup import HEAD

# The front ends: the test's name (its default output folder), the Python
# module whose `python -m` is the server, the notebook's address under the
# server, and what the page's configuration (#jupyter-config-data) must say:
# appName, the start of appVersion, notebookPage. Notebook 7's server loads
# JupyterLab's server extension too (it serves /lab beside /notebooks), so
# the LabApp options below (no extension manager fetching from PyPI, no
# update check) apply to both.
FRONTS = {
    "lab": dict(name="widget_jupyterlab", module="jupyterlab", title="JupyterLab 4",
                path="/lab/tree/widget.ipynb", app="JupyterLab", version="4.", page=None),
    "notebook": dict(name="widget_notebook7", module="notebook", title="Notebook 7",
                     path="/notebooks/widget.ipynb", app="Jupyter Notebook", version="7.",
                     page="notebooks"),
}
FRONT = sys.argv[3] if len(sys.argv) > 3 else "lab"
if FRONT not in FRONTS:
    raise SystemExit("widget_jupyterlab: unknown front end %r (lab or notebook)" % FRONT)
NAME = FRONTS[FRONT]["name"]
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"


def missing():
    """Why the test cannot run here beyond a missing module, or None."""
    if not (os.path.exists(CHROMIUM) and os.path.exists(CHROMEDRIVER)):
        return "chromium or chromedriver is missing (apt-get install chromium chromium-driver)"
    if FRONT == "notebook":
        import notebook
        if int(notebook.__version__.split(".")[0]) != 7:
            return "notebook %s is not Notebook 7" % notebook.__version__
    return None


PYDIR, OUT, _ = widget_setup.start(
    NAME, ["anywidget", FRONTS[FRONT]["module"], "nbformat", "selenium.webdriver"],
    n_args=2, extra_skip=missing)
import nbformat  # noqa: E402
from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.options import Options  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.actions import interaction  # noqa: E402
from selenium.webdriver.common.actions.action_builder import ActionBuilder  # noqa: E402
from selenium.webdriver.common.actions.wheel_input import ScrollOrigin  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402
from selenium.webdriver.support.ui import Select  # noqa: E402

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(fn, timeout, what):
    end = time.monotonic() + timeout
    last = None
    while time.monotonic() < end:
        try:
            last = fn()
        except (SystemExit, KeyboardInterrupt):
            raise
        except Exception:  # the page is still changing
            last = None
        if last:
            return last
        time.sleep(0.2)
    raise TimeoutError("waited %.0f s for %s" % (timeout, what))


CAMERA = ("import json; v.wait(); print('%s', json.dumps({'eye': v.eye, 'at': v.at, "
          "'mode': v.mode, 'preset': v.preset, 'slice_index': v.slice_index, "
          "'stats': v.stats}))")
CELLS = [
    "from volvis.widgets import View\n"
    "v = View(%r, size=(384, 288), preset='ct-bone', slices=True)\n"
    "import json; print('CAM0', json.dumps({'eye': v.eye, 'at': v.at}))\n"
    "v" % str(HEAD),
    CAMERA % "CAM1",
    CAMERA % "CAM2",
]

OUT.mkdir(parents=True, exist_ok=True)
t0 = time.monotonic()
tmp = tempfile.mkdtemp(prefix="volvis-%s-" % FRONT)
rootdir = pathlib.Path(tmp, "root")
rootdir.mkdir()
nb = nbformat.v4.new_notebook()
nb.cells = [nbformat.v4.new_code_cell(c) for c in CELLS]
nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
nbformat.write(nb, str(rootdir / "widget.ipynb"))

port = free_port()
token = base64.b16encode(os.urandom(16)).decode().lower()
env = dict(os.environ, PYTHONPATH=str(PYDIR), JUPYTER_CONFIG_DIR=tmp + "/config",
           JUPYTER_DATA_DIR=tmp + "/data", JUPYTER_RUNTIME_DIR=tmp + "/runtime",
           IPYTHONDIR=tmp + "/ipython", HOME=tmp)
log = open(OUT / "server.log", "w")
server = subprocess.Popen(
    [sys.executable, "-m", FRONTS[FRONT]["module"], "--no-browser", "--ip=127.0.0.1",
     "--port=%d" % port, "--ServerApp.port_retries=0", "--IdentityProvider.token=%s" % token,
     "--ServerApp.root_dir=%s" % rootdir, "--allow-root", "--LabApp.extension_manager=readonly",
     "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate"],
    env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
driver = None
try:
    base = "http://127.0.0.1:%d" % port

    def up():
        if server.poll() is not None:
            raise SystemExit("%s: FAIL the server exited (%d): see %s"
                             % (NAME, server.returncode, OUT / "server.log"))
        with urllib.request.urlopen("%s/api/status?token=%s" % (base, token), timeout=2) as r:
            return r.status == 200
    wait_until(up, 60, "the %s server" % FRONTS[FRONT]["title"])

    opts = Options()
    opts.binary_location = CHROMIUM
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1280,1000", "--user-data-dir=%s/chrome" % tmp):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    driver.get("%s%s?token=%s" % (base, FRONTS[FRONT]["path"], token))
    wait_until(lambda: driver.find_elements(By.CSS_SELECTOR, ".jp-Notebook .jp-Cell"), 90,
               "the notebook")
    # the page is the front end asked for (the server's page configuration)
    page = driver.execute_script(
        "const c = JSON.parse(document.getElementById('jupyter-config-data').textContent);"
        "return [c.appName, c.appVersion, c.notebookPage || null];")
    print("page: %s %s (notebookPage %s)" % tuple(page))
    check(page[0] == FRONTS[FRONT]["app"] and page[1].startswith(FRONTS[FRONT]["version"])
          and page[2] == FRONTS[FRONT]["page"], "the page is %s" % FRONTS[FRONT]["title"])
    # the kernel is ready when the toolbar's status says idle
    wait_until(lambda: driver.execute_script(
        "const s = document.querySelector('.jp-Notebook-ExecutionIndicator');"
        "return s && s.getAttribute('data-status') === 'idle';"), 90, "an idle kernel")

    def started(i):
        """Cell i's prompt shows it queued, running or run: [*] or [n]."""
        cell = driver.find_elements(By.CSS_SELECTOR, ".jp-Notebook .jp-Cell")[i]
        p = cell.find_elements(By.CSS_SELECTOR, ".jp-InputPrompt")
        t = p[0].text if p else ""
        return "*" in t or any(ch.isdigit() for ch in t)

    def run_cell(i):
        """Clicks into cell i's editor and runs it with Shift+Enter; again when its prompt
        does not show it started within 20 s (on a loaded machine a Shift+Enter right after
        the kernel turned idle once only moved the selection: CI, cell 0 left at [ ])."""
        def editor():
            cell = driver.find_elements(By.CSS_SELECTOR, ".jp-Notebook .jp-Cell")[i]
            return [e for e in cell.find_elements(By.CSS_SELECTOR, ".jp-InputArea-editor")
                    if e.is_displayed()]
        for attempt in range(3):
            e = wait_until(editor, 30, "cell %d's editor" % i)[0]
            driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", e)
            ActionChains(driver).move_to_element(e).click().perform()
            ActionChains(driver).key_down(Keys.SHIFT).send_keys(Keys.ENTER).key_up(Keys.SHIFT) \
                .perform()
            try:
                wait_until(lambda: started(i), 20, "cell %d to start" % i)
                return
            except TimeoutError:
                print("cell %d did not start (attempt %d): Shift+Enter again" % (i, attempt + 1))
        raise TimeoutError("cell %d never started" % i)
    run_cell(0)

    def sharp_seq():
        c = driver.find_elements(By.CSS_SELECTOR, "canvas.volvis-canvas")
        if c and c[0].get_attribute("data-sharp") == "1":
            return int(c[0].get_attribute("data-seq"))
        return 0
    seq0 = wait_until(sharp_seq, 90, "the widget's first full frame")
    canvas = driver.find_element(By.CSS_SELECTOR, "canvas.volvis-canvas")
    check(canvas.get_attribute("aria-label").startswith("VolVis 3-D view"),
          "the view has an accessible name")
    labels = [e.get_attribute("aria-label") for e in
              driver.find_elements(By.CSS_SELECTOR, ".volvis-widget select, .volvis-widget input")]
    check({"Rendering mode", "Transfer function preset", "Show slice views",
           "axial slice index"} <= set(labels), "the controls have accessible names: %s" % labels)
    wait_until(lambda: driver.execute_script(
        "return [...document.querySelectorAll('.volvis-slice-canvas')]"
        ".every(c => c.width > 16);"), 30, "the three slice views")
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", canvas)
    time.sleep(0.3)
    before = driver.execute_script("return arguments[0].toDataURL('image/png');", canvas)
    driver.save_screenshot(str(OUT / ("%s_before.png" % FRONT)))

    # a drag across the view, in steps, as a hand does
    kinds = set()
    chain = ActionChains(driver, duration=20)
    chain.move_to_element(canvas).click_and_hold()
    chain.perform()
    for i in range(14):
        ActionChains(driver, duration=20).move_by_offset(10, 3).perform()
        time.sleep(0.05)
        kinds.add(canvas.get_attribute("data-kind"))
    ActionChains(driver).release().perform()
    seq1 = wait_until(lambda: sharp_seq() > seq0 and sharp_seq(), 60,
                      "a full frame after the drag")
    after = driver.execute_script("return arguments[0].toDataURL('image/png');", canvas)
    driver.save_screenshot(str(OUT / ("%s_after.png" % FRONT)))
    check(after != before, "the canvas shows a different frame after the drag (seq %d -> %d)"
          % (seq0, seq1))
    # a reduced frame: a ray-cast preview, or on a loaded machine the ladder's cheapest
    # rung (the box), which the widget drops to when a preview comes too late
    check(any(k and (k.startswith("raycast_1/") or k == "bbox") for k in kinds),
          "reduced frames were shown while dragging: %s" % sorted(k for k in kinds if k))

    # the Python side: the next cell prints the camera traits
    def camera(i):
        run_cell(i)

        def printed():
            text = driver.execute_script(
                "return [...document.querySelectorAll('.jp-OutputArea-output')]"
                ".map(e => e.innerText).join('\\n');")
            return text if "CAM%d" % i in text else None
        text = wait_until(printed, 60, "cell %d's camera" % i)
        cams = {ln[:4]: json.loads(ln[4:]) for ln in text.splitlines() if ln.startswith("CAM")}
        return cams["CAM0"], cams["CAM%d" % i]

    def dist(c):
        return sum((a - b) ** 2 for a, b in zip(c["eye"], c["at"])) ** 0.5
    cam0, cam1 = camera(1)
    moved = sum((a - b) ** 2 for a, b in zip(cam0["eye"], cam1["eye"])) ** 0.5
    check(moved > 1.0, "the eye trait moved by %.1f world units: %s -> %s"
          % (moved, cam0["eye"], cam1["eye"]))
    check(abs(dist(cam1) - dist(cam0)) < 1e-6 * dist(cam0),
          "the drag orbited: the eye's distance from the look-at point is kept")
    print("stats:", cam1["stats"])

    # the wheel (300 px up: 1.1^3 closer) and a two-finger pinch (touch pointers
    # spreading from 60 to 180 px apart: 3 times closer, the midpoint fixed),
    # on the view scrolled whole into the page again (running cell 1 scrolled
    # the notebook: the pointers must not land on the toolbar above it)
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'});", canvas)
    ActionChains(driver).scroll_from_origin(ScrollOrigin.from_element(canvas), 0, -300) \
        .perform()
    seq2 = wait_until(lambda: sharp_seq() > seq1 and sharp_seq(), 60, "a full frame after the wheel")
    ab = ActionBuilder(driver)
    f1 = ab.add_pointer_input(interaction.POINTER_TOUCH, "finger1")
    f2 = ab.add_pointer_input(interaction.POINTER_TOUCH, "finger2")
    f1.create_pointer_move(x=-30, y=0, origin=canvas)
    f2.create_pointer_move(x=30, y=0, origin=canvas)
    f1.create_pointer_down()
    f2.create_pointer_down()
    for k in range(1, 7):
        f1.create_pointer_move(x=-30 - 10 * k, y=0, origin=canvas, duration=30)
        f2.create_pointer_move(x=30 + 10 * k, y=0, origin=canvas, duration=30)
    f1.create_pointer_up(0)
    f2.create_pointer_up(0)
    ab.perform()
    seq3 = wait_until(lambda: sharp_seq() > seq2 and sharp_seq(), 60,
                      "a full frame after the pinch")
    driver.save_screenshot(str(OUT / ("%s_zoomed.png" % FRONT)))
    # the menus set the mode and preset traits
    Select(driver.find_element(By.CSS_SELECTOR, "select.volvis-mode")).select_by_value("mip")
    wait_until(lambda: sharp_seq() > seq3 and sharp_seq(), 60, "a full frame after the mode")
    Select(driver.find_element(By.CSS_SELECTOR, "select.volvis-preset")) \
        .select_by_value("ct-soft-tissue")
    # a key on the focused view: + zooms 1.1 times
    seq4 = wait_until(lambda: sharp_seq(), 60, "a full frame after the preset")
    canvas.send_keys("+")
    wait_until(lambda: sharp_seq() > seq4, 60, "a full frame after the + key")
    # the axial slice slider
    driver.execute_script(
        "const r = document.querySelector('.volvis-slice input[aria-label=\"axial slice index\"]');"
        "r.value = '10'; r.dispatchEvent(new Event('input'));")
    label = wait_until(lambda: driver.execute_script(
        "const t = document.querySelector('.volvis-slice figcaption span').textContent;"
        "return t.startsWith('axial 11/') ? t : null;"), 30, "the axial view at slice 10")
    _, cam2 = camera(2)
    ratio = dist(cam1) / dist(cam2)
    want = 1.1 ** 3 * 3.0 * 1.1
    check(cam2["mode"] == "mip" and cam2["preset"] == "ct-soft-tissue",
          "the menus set mode and preset: %s, %s" % (cam2["mode"], cam2["preset"]))
    check(abs(ratio / want - 1) < 0.02, "wheel, pinch and + key zoomed %.3f times "
          "(want 1.1^3 x 3 x 1.1 = %.3f)" % (ratio, want))
    check(cam2["slice_index"].get("axial") == 10, "the slider moved the axial view: %s, %r"
          % (cam2["slice_index"], label))
except BaseException:
    if driver is not None:
        driver.save_screenshot(str(OUT / ("%s_failed.png" % FRONT)))
        print("page: motions sent %s, frames drawn %s" % tuple(driver.execute_script(
            "const r = document.querySelector('.volvis-widget');"
            "return r ? [r.dataset.motions, r.dataset.frames] : [null, null];")))
        for e in driver.get_log("browser")[-20:]:
            print("browser:", e.get("level"), e.get("message", "")[:300])
    raise
finally:
    if driver is not None:
        try:
            driver.quit()
        except Exception as e:
            print("browser: %s" % e)
    try:
        os.killpg(server.pid, signal.SIGTERM)
        server.wait(20)
    except (subprocess.TimeoutExpired, ProcessLookupError):
        try:
            os.killpg(server.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        server.wait(10)
    log.close()
    shutil.rmtree(tmp, ignore_errors=True)
print("%s: %.1f s, %d failures" % (NAME, time.monotonic() - t0, len(failures)))
sys.exit(1 if failures else 0)
