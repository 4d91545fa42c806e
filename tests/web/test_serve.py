#!/usr/bin/python3
"""Browser tests of `volvis serve` and its client (web/), in one process.

Headless Chromium, driven through selenium, uses the page as a person does
(it sees the CT head, drags it round, reads a value under the pointer,
saves the session, downloads a PNG, opens a second tab); raw HTTP and
WebSocket clients send what a browser would not (no token, a foreign
Origin, garbage, a hang-up in the middle of a frame).

usage: test_serve.py [VOLVIS [DATA_DIR [OUT_DIR]]]
  VOLVIS    the volvis binary (else $VOLVIS_BIN, else build/release/volvis)
  DATA_DIR  the shared data folder (else $VV_DATA_DIR, else ../shared/data)
  OUT_DIR   screenshots, logs and PNGs (else $VV_TEST_OUT/web_serve, else a
            temporary folder)

Exits 77 (CTest's SKIP_RETURN_CODE) when Chromium, chromedriver, selenium,
websockets or PIL is missing: a test that cannot run is skipped, never passed.
Every wait polls for a state with a generous deadline (a loaded 2-core
machine renders slowly); no sleep is an assertion.
"""
import array
import asyncio
import base64
import io
import json
import math
import os
import re
import select
import shutil
import subprocess
import sys
import tempfile
import time
import unittest
import urllib.error
import urllib.request

SKIP = 77
CHROMIUM = os.environ.get('CHROMIUM', '/usr/bin/chromium')
CHROMEDRIVER = os.environ.get('CHROMEDRIVER', '/usr/bin/chromedriver')

try:
    from PIL import Image, ImageChops
    import websockets
    from selenium import webdriver
    from selenium.common.exceptions import WebDriverException
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.actions.action_builder import ActionBuilder
    from selenium.webdriver.common.actions.mouse_button import MouseButton
    from selenium.webdriver.common.actions.wheel_input import ScrollOrigin
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select
except ImportError as e:  # pragma: no cover - depends on the machine
    print(f'test_serve: skipped: {e} (apt install python3-selenium python3-websockets python3-pil)')
    sys.exit(SKIP)
for exe in (CHROMIUM, CHROMEDRIVER):
    if not os.access(exe, os.X_OK):
        print(f'test_serve: skipped: {exe} is missing (apt install chromium chromium-driver)')
        sys.exit(SKIP)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ARGS = sys.argv[1:]
VOLVIS = os.path.abspath(ARGS[0] if len(ARGS) > 0 else
                         os.environ.get('VOLVIS_BIN', os.path.join(ROOT, 'build/release/volvis')))
DATA = os.path.abspath(ARGS[1] if len(ARGS) > 1 else
                       os.environ.get('VV_DATA_DIR', os.path.join(ROOT, '..', 'shared', 'data')))
if len(ARGS) > 2:
    OUT = os.path.abspath(ARGS[2])
elif os.environ.get('VV_TEST_OUT'):
    OUT = os.path.join(os.environ['VV_TEST_OUT'], 'web_serve')
else:
    OUT = tempfile.mkdtemp(prefix='vv_web_serve_out_')
CT_HEAD = os.path.join(DATA, 'volumes', 'ct_head.nrrd')

# Deadlines, seconds: generous, since a full frame of the CT head takes
# a fraction of a second on a free machine and many on a loaded one.
START_S = 60
WAIT_S = 120

SERVER = None  # the one `volvis serve` of the module
DRIVER = None  # the one Chromium


def log(*a):
    print('test_serve:', *a, flush=True)


# ---- the server ----------------------------------------------------------------------------

REMOTE_PREFIX = 'http://127.0.0.1:9/data/'
REMOTE_URL = 'http://127.0.0.1:9/given.ome.zarr'


class Server:
    """`volvis serve --port 0 --root ROOT --allow-url REMOTE_PREFIX REMOTE_URL FILE`; its
    URL is read from its stdout."""

    def __init__(self, root, file):
        self.stderr = open(os.path.join(OUT, 'serve.log'), 'w')
        # remote data the page lists (nothing listens on port 9: opening one is the
        # door's one-line error, today and once the build reads URLs)
        self.proc = subprocess.Popen([VOLVIS, 'serve', '--port', '0', '--root', root,
                                      '--allow-url', REMOTE_PREFIX, REMOTE_URL, file],
                                     stdout=subprocess.PIPE, stderr=self.stderr)
        deadline = time.time() + START_S
        out = b''
        while not out.endswith(b'\n'):
            left = deadline - time.time()
            if left <= 0 or self.proc.poll() is not None:
                self.stop()
                raise RuntimeError(f'volvis serve printed no URL ({out!r}); see {self.stderr.name}')
            if select.select([self.proc.stdout], [], [], min(left, 1))[0]:
                out += os.read(self.proc.stdout.fileno(), 4096)
        line = out.decode('ascii', 'replace')
        m = re.fullmatch(r'(http://127\.0\.0\.1:(\d+))/\?token=([0-9a-f]+)\n', line)
        if not m:
            raise RuntimeError(f'volvis serve printed {line!r}, not http://127.0.0.1:PORT/?token=T')
        self.url = line.strip()
        self.origin, self.port, self.token = m.group(1), int(m.group(2)), m.group(3)
        self.ws_url = f'ws://127.0.0.1:{self.port}/ws'

    def alive(self):
        return self.proc.poll() is None

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc.stdout.close()
        self.stderr.close()


# ---- raw clients ---------------------------------------------------------------------------

def http_get(path, headers=None):
    """(status, headers, body) of GET path on the server, errors included."""
    req = urllib.request.Request(SERVER.origin + path, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, r.headers, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read()


def parse_binary(data):
    kind = data[:4].decode('ascii')
    n = int.from_bytes(data[4:8], 'little')
    return kind, json.loads(data[8:8 + n]), data[8 + n:]


def ws_connect(origin=None, cookie=True):
    headers = {'Cookie': f'volvis_token={SERVER.token}'} if cookie else {}
    return websockets.connect(SERVER.ws_url, subprotocols=['volvis'],
                              origin=origin or SERVER.origin, extra_headers=headers,
                              max_size=64 << 20, open_timeout=START_S, close_timeout=10)


async def hello_and_frame(ws, width=200, height=150):
    """Says hello; returns (state, FRME header) once both came."""
    await ws.send(json.dumps({'type': 'hello', 'width': width, 'height': height}))
    state = frame = None
    deadline = time.time() + WAIT_S
    while state is None or frame is None:
        msg = await asyncio.wait_for(ws.recv(), max(1, deadline - time.time()))
        if isinstance(msg, bytes):
            kind, header, _ = parse_binary(msg)
            if kind == 'FRME':
                frame = header
        else:
            m = json.loads(msg)
            if m['type'] == 'state':
                state = m
    return state, frame


async def closed_by_server(ws, send):
    """Sends `send` (str or bytes), then reads until the server closes; returns the close code."""
    await ws.send(send)
    deadline = time.time() + WAIT_S
    try:
        while time.time() < deadline:
            await asyncio.wait_for(ws.recv(), max(1, deadline - time.time()))
    except websockets.ConnectionClosed:
        return ws.close_code
    raise AssertionError(f'the server did not close a client that sent {send[:60]!r}')


def run(coro):
    return asyncio.run(coro)


# ---- the browser ---------------------------------------------------------------------------

def start_chromium():
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for a in ('--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage',
              '--window-size=1280,800', '--hide-scrollbars', '--mute-audio'):
        opts.add_argument(a)
    opts.add_experimental_option('prefs', {'download.default_directory': OUT,
                                           'download.prompt_for_download': False})
    opts.set_capability('goog:loggingPrefs', {'browser': 'ALL'})
    d = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    d.set_script_timeout(60)
    return d


def page_setup(d):
    """A 1280 x 800 viewport (the window's size includes no browser chrome headless, but be sure)."""
    d.execute_cdp_cmd('Emulation.setDeviceMetricsOverride',
                      {'width': 1280, 'height': 800, 'deviceScaleFactor': 1, 'mobile': False})
    d.execute_cdp_cmd('Browser.setDownloadBehavior', {'behavior': 'allow', 'downloadPath': OUT})


def js(expr, *args):
    return DRIVER.execute_script('return ' + expr, *args)


def wait_for(what, cond, timeout=WAIT_S):
    """Polls cond() (a callable, or a JS expression) until it is truthy; returns its value."""
    deadline = time.time() + timeout
    last = None
    while time.time() < deadline:
        try:
            last = cond() if callable(cond) else js(cond)
        except WebDriverException as e:
            last = e
        if last and not isinstance(last, Exception):
            return last
        time.sleep(0.1)
    shot('timeout_' + re.sub(r'\W+', '_', what)[:40])
    raise AssertionError(f'waited {timeout} s for {what}; last: {last!r}; '
                         f'page errors: {safe_js("window.volvis && window.volvis.errors")}')


def safe_js(expr):
    try:
        return js(expr)
    except WebDriverException as e:
        return f'({e.msg})'


def shot(name):
    path = os.path.join(OUT, name + '.png')
    DRIVER.save_screenshot(path)
    return path


def element_image(elem_id):
    """What the screen shows of an element, as an RGB PIL image."""
    png = DRIVER.find_element(By.ID, elem_id).screenshot_as_png
    return Image.open(io.BytesIO(png)).convert('RGB')


def bright_fraction(img, level=40):
    """The fraction of pixels brighter than `level` (of 255): on a black background, what shows the data."""
    grey = img.convert('L')
    hist = grey.histogram()
    return sum(hist[level:]) / (grey.width * grey.height)


def assert_shows_data(case, img, what):
    """Not blank: a good part of the image is lit, and some of it is bright."""
    frac = bright_fraction(img)
    top = img.convert('L').getextrema()[1]
    case.assertGreater(frac, 0.05, f'{what}: only {frac:.1%} of the pixels are lit')
    case.assertGreaterEqual(top, 100, f'{what}: the brightest pixel is {top} of 255')
    return frac


def mean_abs_diff(a, b):
    if a.size != b.size:
        b = b.resize(a.size)
    hist = ImageChops.difference(a, b).convert('L').histogram()
    return sum(i * n for i, n in enumerate(hist)) / (a.width * a.height)


def wait_sharp_after(seq_before, what):
    """A sharp frame after frame seq_before that shows every nav message sent; its header."""
    return wait_for(what, lambda: js('volvis.lastFrame && volvis.lastFrame.seq > arguments[0] && '
                                     'volvis.lastFrame.sharp && '
                                     'volvis.lastFrame.input_seq >= volvis.navSeq && volvis.lastFrame',
                                     seq_before))


def click(elem):
    """Clicks elem after scrolling it to the middle of its scrolling panel: selenium's own
    scrolling may leave it at the panel's edge, under the status line."""
    DRIVER.execute_script('arguments[0].scrollIntoView({block: "center"})', elem)
    elem.click()


def drag_view(dx=120, dy=40, steps=6):
    """A left drag across the 3-D view, in steps (several pointermoves, as a hand makes)."""
    view = DRIVER.find_element(By.ID, 'view3d')
    chain = ActionChains(DRIVER).move_to_element(view).click_and_hold()
    for _ in range(steps):
        chain = chain.move_by_offset(dx // steps, dy // steps).pause(0.03)
    chain.release().perform()


def open_page():
    """The token URL in the current tab; returns once the first frame is drawn."""
    DRIVER.get(SERVER.url)
    page_setup(DRIVER)
    wait_for('the socket to open', 'window.volvis && window.volvis.connected')
    wait_for('the first frame', 'window.volvis.frames > 0 && volvis.state && volvis.lastFrame.sharp')


def write_cells(folder):
    """cells.nrrd: three channels (blobs) over three time steps, the blobs moving in x; and
    cells_scene.json, a scene that shows its channels as one object."""
    X, Y, Z, T, C = 32, 32, 24, 3, 3
    centres = [(0.3, 0.4, 0.5), (0.65, 0.6, 0.5), (0.5, 0.3, 0.4)]
    vals = array.array('h')
    for t in range(T):
        for z in range(Z):
            for y in range(Y):
                for x in range(X):
                    for cx, cy, cz in centres:
                        d2 = ((x / X - cx - 0.1 * t) ** 2 + (y / Y - cy) ** 2 + (z / Z - cz) ** 2)
                        vals.append(int(3000 * math.exp(-d2 / 0.02)))
    if sys.byteorder != 'little':
        vals.byteswap()
    with open(os.path.join(folder, 'cells.nrrd'), 'wb') as f:
        f.write((f'NRRD0004\ntype: short\ndimension: 5\nsizes: {C} {X} {Y} {Z} {T}\n'
                 'kinds: RGB-color space space space time\nencoding: raw\nendian: little\n\n').encode())
        f.write(vals.tobytes())
    with open(os.path.join(folder, 'cells_scene.json'), 'w') as f:
        json.dump({'objects': [{'file': 'cells.nrrd', 'blend': 'maximum', 'channels': [
            {'channel': 0, 'name': 'nuclei'}, {'channel': 1, 'name': 'membrane'},
            {'channel': 2, 'name': 'protein'}]}]}, f)


def setUpModule():
    try:
        start()
    except BaseException:
        tearDownModule()  # unittest does not, when setUpModule fails
        raise


def start():
    global SERVER, DRIVER, ROOT_DIR
    os.makedirs(OUT, exist_ok=True)
    if not os.access(VOLVIS, os.X_OK):
        raise RuntimeError(f'{VOLVIS}: not an executable (give the volvis binary)')
    if not os.path.exists(CT_HEAD):
        raise RuntimeError(f'{CT_HEAD} is missing (give the shared data folder)')
    # The root the page may browse and save into: a temporary folder with a
    # copy of the CT head (the shared data is never written).
    ROOT_DIR = tempfile.mkdtemp(prefix='vv_web_root_')
    os.makedirs(os.path.join(ROOT_DIR, 'sub'))
    shutil.copyfile(CT_HEAD, os.path.join(ROOT_DIR, 'ct_head.nrrd'))
    write_cells(ROOT_DIR)
    SERVER = Server(ROOT_DIR, os.path.join(ROOT_DIR, 'ct_head.nrrd'))
    log('server', SERVER.url, 'out', OUT)
    DRIVER = start_chromium()
    open_page()


def tearDownModule():
    global SERVER, DRIVER, ROOT_DIR
    if DRIVER:
        try:
            for e in DRIVER.get_log('browser'):
                log('browser:', e['level'], e['message'][:300])
        except WebDriverException:
            pass
        DRIVER.quit()
        DRIVER = None
    if SERVER:
        SERVER.stop()
        SERVER = None
    if ROOT_DIR:
        shutil.rmtree(ROOT_DIR, ignore_errors=True)
        ROOT_DIR = None


ROOT_DIR = None


# ---- the tests -----------------------------------------------------------------------------
# unittest runs them in the order of their names; each leaves the first tab
# selected and connected.

class T01Page(unittest.TestCase):
    def test_head_is_shown(self):
        """The 3-D view shows the CT head: a sharp frame drawn, a good part of the view bright."""
        wait_for('the slices', 'document.getElementById("probe-axial") && '
                 '[...document.querySelectorAll(".preset img")].length > 0')
        img = element_image('view3d')
        path = shot('01_page')
        frac = assert_shows_data(self, img, 'the 3-D view')
        log(f'view {img.size}, {frac:.1%} lit; screenshot {path}')
        h = js('volvis.lastFrame')
        self.assertTrue(h['sharp'])
        self.assertEqual(js('volvis.state.name'), 'ct_head.nrrd')
        self.assertEqual(js('volvis.state.dims'), [256, 256, 108])
        self.assertEqual(js('volvis.errors'), [])
        # the token left the address bar (the cookie carries it)
        self.assertNotIn('token', DRIVER.current_url)
        # every slice view shows an image (not all black)
        for axis in ('axial', 'coronal', 'sagittal'):
            assert_shows_data(self, element_image(f'slice-{axis}'), f'the {axis} slice')

    def test_no_csp_violations(self):
        """The page runs under the server's strict CSP without a violation (no inline code)."""
        logs = DRIVER.get_log('browser')
        bad = [e['message'] for e in logs if 'Content Security Policy' in e['message']]
        self.assertEqual(bad, [])

    def test_controls_have_names(self):
        """Every control of the page has an accessible name (a label or aria-label)."""
        unnamed = js('''[...document.querySelectorAll('button, input, select, canvas[tabindex]')]
            .filter(e => !e.closest('[hidden]'))
            .filter(e => !(e.getAttribute('aria-label') || (e.labels && e.labels.length) ||
                           e.getAttribute('aria-labelledby') || e.textContent.trim()))
            .map(e => e.outerHTML.slice(0, 80))''')
        self.assertEqual(unnamed, [])
        for i in ('view3d', 'slice-axial', 'slice-coronal', 'slice-sagittal', 'slice-axial-index',
                  'slice-coronal-index', 'slice-sagittal-index', 'probe-axial', 'window', 'level',
                  'mode', 'isovalue', 'presets', 'time', 'files', 'save-path', 'save', 'png',
                  'status'):
            self.assertTrue(DRIVER.find_elements(By.ID, i), f'no element #{i}')


class T02Navigation(unittest.TestCase):
    def test_drag_rotates(self):
        """A mouse drag on the 3-D view changes the image: the sharp frame after it differs."""
        before_img = element_image('view3d')
        seq = js('volvis.lastFrame.seq')
        nav_before = js('volvis.navSeq')
        drag_view(150, 30)
        h = wait_sharp_after(seq, 'a sharp frame after the drag')
        self.assertGreater(js('volvis.navSeq'), nav_before + 1, 'the drag sent no nav messages')
        after_img = element_image('view3d')
        shot('02_after_drag')
        d = mean_abs_diff(before_img, after_img)
        log(f'drag: frame {h["seq"]} ({h["kind"]}), mean difference {d:.1f} grey levels')
        self.assertGreater(d, 2.0, 'the view did not change with the drag')
        assert_shows_data(self, after_img, 'the view after the drag')

    def test_wheel_zooms(self):
        """The wheel zooms: scrolling up brings the head closer (more of the view lit), down moves it away."""
        view = DRIVER.find_element(By.ID, 'view3d')
        lit = bright_fraction(element_image('view3d'))
        for notches, closer in ((-3, True), (3, False)):
            seq = js('volvis.lastFrame.seq')
            nav = js('volvis.navSeq')
            for _ in range(abs(notches)):
                ActionChains(DRIVER).scroll_from_origin(
                    ScrollOrigin.from_element(view), 0, 100 * (1 if notches > 0 else -1)).perform()
            wait_sharp_after(seq, 'a sharp frame after the wheel')
            self.assertGreater(js('volvis.navSeq'), nav, 'the wheel sent no nav message')
            now = bright_fraction(element_image('view3d'))
            log(f'wheel {notches:+d}: lit {lit:.1%} -> {now:.1%}')
            if closer:
                self.assertGreater(now, lit * 1.1)
            else:
                self.assertLess(now, lit * 0.95)
            lit = now

    def test_touch_pinch_zooms(self):
        """Two fingers moving apart zoom in; one finger dragging rotates (touch input through CDP)."""
        r = js('document.getElementById("view3d").getBoundingClientRect().toJSON()')
        cx, cy = r['x'] + r['width'] / 2, r['y'] + r['height'] / 2

        def touch(kind, points):
            DRIVER.execute_cdp_cmd('Input.dispatchTouchEvent', {
                'type': kind, 'touchPoints': [{'x': x, 'y': y, 'id': i} for i, (x, y) in points]})

        lit = bright_fraction(element_image('view3d'))
        seq = js('volvis.lastFrame.seq')
        touch('touchStart', [(0, (cx - 40, cy)), (1, (cx + 40, cy))])
        for k in range(1, 9):
            touch("touchMove", [(0, (cx - 40 - 3 * k, cy)), (1, (cx + 40 + 3 * k, cy))])
        touch('touchEnd', [])
        wait_sharp_after(seq, 'a sharp frame after the pinch')
        now = bright_fraction(element_image('view3d'))
        log(f'pinch: lit {lit:.1%} -> {now:.1%}')
        self.assertGreater(now, lit * 1.1, 'spreading two fingers did not zoom in')

        before = element_image('view3d')
        seq = js('volvis.lastFrame.seq')
        touch('touchStart', [(0, (cx, cy))])
        for k in range(1, 9):
            touch('touchMove', [(0, (cx + 15 * k, cy))])
        touch('touchEnd', [])
        wait_sharp_after(seq, 'a sharp frame after the one-finger drag')
        self.assertGreater(mean_abs_diff(before, element_image('view3d')), 2.0,
                           'a one-finger drag did not turn the view')
        click(DRIVER.find_element(By.ID, 'reset-view'))
        wait_sharp_after(js('volvis.lastFrame.seq'), 'the reset view')


class T03Slices(unittest.TestCase):
    def test_probe_shows_value(self):
        """The pointer over the axial slice shows the value there, the one `volvis slice --probe` reads."""
        el = DRIVER.find_element(By.ID, 'slice-axial')
        js('document.getElementById("probe-axial").textContent = ""')
        ActionChains(DRIVER).move_to_element(el).move_by_offset(3, 2).perform()
        unit = js('volvis.state.value_unit')
        self.assertEqual(unit, 'HU')  # a CT in Hounsfield units, as the server says
        text = wait_for('the probe text', lambda: re.fullmatch(
            r'(-?\d+(?:\.\d+)?) HU at \((\d+), (\d+), (\d+)\)',
            DRIVER.find_element(By.ID, 'probe-axial').text))
        probe = js('volvis.lastProbe')
        log('probe:', text.group(0), probe)
        self.assertEqual(probe['axis'], 'axial')
        self.assertIsInstance(probe['value'], (int, float))
        # the same point through the library's own probe, from the command line
        x, y, z = probe['world']
        out = subprocess.run([VOLVIS, 'slice', os.path.join(ROOT_DIR, 'ct_head.nrrd'),
                              '--probe', f'{x!r},{y!r},{z!r}', '-q'],
                             capture_output=True, text=True, timeout=WAIT_S)
        self.assertEqual(out.returncode, 0, out.stderr)
        cli_value = float(re.match(r'value (\S+)', out.stdout).group(1))
        self.assertAlmostEqual(probe['value'], cli_value, delta=1e-3 * max(1, abs(cli_value)))
        shot('03_probe')

    def test_click_links_cursor(self):
        """A click on the axial slice moves the coronal and sagittal views through the clicked voxel."""
        el = DRIVER.find_element(By.ID, 'slice-axial')
        ActionChains(DRIVER).move_to_element(el).move_by_offset(-25, 15).click().perform()
        probe = wait_for('the probe of the click', lambda: (
            lambda p: p if p and p['axis'] == 'axial' and p.get('indices') else None)(
                js('volvis.lastProbe')))
        want = probe['indices']
        got = wait_for('the other views to follow', lambda: (
            lambda c, s: (c, s) if (c, s) == (want['coronal'], want['sagittal']) else None)(
                int(DRIVER.find_element(By.ID, 'slice-coronal-index').get_attribute('value')),
                int(DRIVER.find_element(By.ID, 'slice-sagittal-index').get_attribute('value'))))
        log('cursor', [round(v) for v in probe['ijk']], 'indices', want, 'sliders', got)
        shot('03_cursor')


    def test_slice_index_and_window_level(self):
        """The slider and the wheel step through slices; a right drag on a slice sets window and level."""
        slider = DRIVER.find_element(By.ID, 'slice-sagittal-index')
        start = int(slider.get_attribute('value'))
        before = element_image('slice-sagittal')
        slider.send_keys(*[Keys.ARROW_LEFT] * 30)
        wait_for('the slider', lambda: int(slider.get_attribute('value')) == start - 30)
        wait_for('the sagittal slice 30 back', lambda: mean_abs_diff(before, element_image('slice-sagittal')) > 2)
        self.assertEqual(DRIVER.find_element(By.ID, 'slice-sagittal-index-value').text,
                         f'{start - 30 + 1}/{js("volvis.state.slices.sagittal")}')
        el = DRIVER.find_element(By.ID, 'slice-sagittal')
        for _ in range(4):
            ActionChains(DRIVER).scroll_from_origin(ScrollOrigin.from_element(el), 0, 100).perform()
        wait_for('the wheel to step back 4 slices',
                 lambda: int(slider.get_attribute('value')) == start - 34)

        window, level = (float(DRIVER.find_element(By.ID, i).get_attribute('value'))
                         for i in ('window', 'level'))
        before = element_image('slice-axial')
        a = ActionBuilder(DRIVER)
        a.pointer_action.move_to(DRIVER.find_element(By.ID, 'slice-axial')).pointer_down(MouseButton.RIGHT)
        for _ in range(4):
            a.pointer_action.move_by(-20, 15)
        a.pointer_action.pointer_up(MouseButton.RIGHT)
        a.perform()
        got = wait_for('window and level to change', lambda: (lambda w, l: (w, l) if w < window and l > level
                       else None)(*(float(DRIVER.find_element(By.ID, i).get_attribute('value'))
                                    for i in ('window', 'level'))))
        wait_for('the axial slice with them', lambda: mean_abs_diff(before, element_image('slice-axial')) > 2)
        log(f'window/level {window:g}/{level:g} -> {got[0]:g}/{got[1]:g}')
        self.assertFalse(js('volvis.closed'), 'the drag closed the socket')
        shot('03_window_level')
        click(DRIVER.find_element(By.ID, 'wl-auto'))
        wait_for('the auto window', lambda: float(DRIVER.find_element(By.ID, 'window').get_attribute('value'))
                 == float(f'{window:g}'))


class T04SaveAndPng(unittest.TestCase):
    def test_png_equals_render_of_saved_session(self):
        """The PNG of the view (button PNG) is, pixel for pixel, `volvis render` of the saved session."""
        seq = js('volvis.lastFrame.seq')
        drag_view(-60, 50)
        wait_sharp_after(seq, 'a sharp frame after the drag')
        path_in = DRIVER.find_element(By.ID, 'save-path')
        path_in.clear()
        path_in.send_keys('sub/saved.json')
        saved = os.path.join(ROOT_DIR, 'sub', 'saved.json')
        click(DRIVER.find_element(By.ID, 'save'))
        wait_for('the saved session', lambda: os.path.exists(saved) and
                 'saved' in DRIVER.find_element(By.ID, 'status').text)
        js('volvis.lastPng = null')
        for f in os.listdir(OUT):
            if f.startswith('ct_head') and f.endswith('.png'):
                os.remove(os.path.join(OUT, f))
        click(DRIVER.find_element(By.ID, 'png'))
        b64 = wait_for('the PNG', lambda: js('''volvis.lastPng && (() => {
            let s = ''; const b = volvis.lastPng;
            for (let i = 0; i < b.length; i += 32768) s += String.fromCharCode(...b.subarray(i, i + 32768));
            return btoa(s); })()'''))
        png = base64.b64decode(b64)
        with open(os.path.join(OUT, '04_view.png'), 'wb') as f:
            f.write(png)
        shutil.copyfile(saved, os.path.join(OUT, '04_saved.json'))
        rendered = os.path.join(OUT, '04_render.png')
        r = subprocess.run([VOLVIS, 'render', saved, '-o', rendered, '-q'],
                           capture_output=True, text=True, timeout=600)
        self.assertEqual(r.returncode, 0, r.stderr)
        a = Image.open(io.BytesIO(png))
        b = Image.open(rendered)
        log(f'PNG {a.size} {a.mode}; render {b.size} {b.mode}')
        self.assertEqual(a.size, b.size)
        # the view's size when the session was saved (not volvis.state now:
        # on a loaded machine a resize the page's layout sent before may
        # reach the server after the PNG, and the state be newer than both)
        with open(saved) as f:
            view = json.load(f)['view']
        self.assertEqual(a.size, (view['width'], view['height']))
        a, b = a.convert('RGBA'), b.convert('RGBA')
        diff = ImageChops.difference(a, b)
        if diff.getbbox():
            diff.save(os.path.join(OUT, '04_diff.png'))
        self.assertIsNone(diff.getbbox(), 'the PNG of the view differs from the saved session rendered')
        assert_shows_data(self, a.convert('RGB'), 'the PNG')
        # the button downloads it too: the same bytes
        dl = wait_for('the download', lambda: [f for f in os.listdir(OUT)
                                               if f.startswith('ct_head') and f.endswith('.png')])
        def downloaded():
            with open(os.path.join(OUT, dl[0]), 'rb') as f:
                b = f.read()
            return b if b == png else None
        got = wait_for('the downloaded file to be complete', downloaded)
        self.assertEqual(got, png)


class T05Http(unittest.TestCase):
    def test_no_token_forbidden(self):
        """Without the token (no cookie, no query) the page and its files are 403, never served."""
        for path in ('/', '/index.html', '/js/main.js', '/style.css', '/?token=' + '0' * 48):
            status, headers, body = http_get(path)
            self.assertEqual(status, 403, path)
            self.assertNotIn(b'<script', body)

    def test_token_and_headers(self):
        """With the token: the page, the cookie (HttpOnly, SameSite=Strict) and the strict headers."""
        status, headers, body = http_get('/?token=' + SERVER.token)
        self.assertEqual(status, 200)
        self.assertIn(b'js/main.js', body)
        cookie = headers.get('Set-Cookie', '')
        self.assertIn(f'volvis_token={SERVER.token}', cookie)
        self.assertIn('HttpOnly', cookie)
        self.assertIn('SameSite=Strict', cookie)
        csp = headers.get('Content-Security-Policy', '')
        self.assertIn("default-src 'self'", csp)
        self.assertIn("style-src 'self'", csp)
        self.assertEqual(headers.get('X-Content-Type-Options'), 'nosniff')
        self.assertIn('no-store', headers.get('Cache-Control', ''))
        status, headers, body = http_get('/js/main.js', {'Cookie': f'volvis_token={SERVER.token}'})
        self.assertEqual(status, 200)
        status, _, _ = http_get('/no-such-file.js', {'Cookie': f'volvis_token={SERVER.token}'})
        self.assertEqual(status, 404)


class T06WebSocket(unittest.TestCase):
    def test_foreign_origin_refused(self):
        """An upgrade from another Origin is refused, though it has the cookie; the page's own Origin is not."""
        async def go():
            with self.assertRaises(websockets.InvalidHandshake):
                async with ws_connect(origin='http://evil.example') as ws:
                    await ws.recv()
            with self.assertRaises(websockets.InvalidHandshake):
                async with ws_connect(cookie=False) as ws:
                    await ws.recv()
            async with ws_connect() as ws:  # the control: the same client, the right Origin
                state, frame = await hello_and_frame(ws)
                self.assertEqual(state['name'], 'ct_head.nrrd')
        run(go())

    def test_garbage_closes_that_client_only(self):
        """Non-JSON, over 64 KiB, unknown types, ill-typed fields and binary frames close that client; others go on."""
        garbage = [
            'this is not JSON',
            json.dumps({'type': 'hello', 'width': 100, 'height': 100, 'pad': 'x' * 70000}),
            json.dumps({'type': 'no-such-type'}),
            json.dumps({'type': 'hello', 'width': 'wide', 'height': 100}),
            json.dumps({'type': 'nav', 'motion': 'zoom', 'factor': -1}),
            json.dumps([1, 2, 3]),
            b'\x00\x01binary\xff' * 10,
        ]

        async def go():
            async with ws_connect() as other:
                await hello_and_frame(other)
                for g in garbage:
                    async with ws_connect() as ws:
                        await hello_and_frame(ws)
                        code = await closed_by_server(ws, g)
                        self.assertIn(code, (1002, 1003, 1007, 1008, 1009), repr(g)[:60])
                # the one that behaved still gets frames
                await other.send(json.dumps({'type': 'nav', 'motion': 'rotate', 'dx': 30, 'dy': 0,
                                             'seq': 1, 'moving': False}))
                deadline = time.time() + WAIT_S
                while True:
                    msg = await asyncio.wait_for(other.recv(), max(1, deadline - time.time()))
                    if isinstance(msg, bytes) and parse_binary(msg)[0] == 'FRME' and \
                            parse_binary(msg)[1]['input_seq'] == 1:
                        break
        run(go())
        self.assertTrue(SERVER.alive())
        self.assert_page_still_works()

    def test_hang_up_mid_frame(self):
        """Clients that leave while their first frame renders (closed or cut off) harm no one."""
        async def go():
            for _ in range(3):
                ws = await ws_connect()
                await ws.send(json.dumps({'type': 'hello', 'width': 800, 'height': 600}))
                await ws.close()
                ws = await ws_connect()
                await ws.send(json.dumps({'type': 'hello', 'width': 800, 'height': 600}))
                await ws.send(json.dumps({'type': 'png'}))
                ws.transport.abort()  # no closing handshake: a cable pulled
            async with ws_connect() as ws:
                state, frame = await hello_and_frame(ws)
                self.assertEqual(state['name'], 'ct_head.nrrd')
        run(go())
        self.assertTrue(SERVER.alive())
        self.assert_page_still_works()

    def assert_page_still_works(self):
        seq = js('volvis.lastFrame.seq')
        drag_view(40, 0, steps=2)
        wait_sharp_after(seq, 'a frame in the page after the other clients')
        self.assertTrue(js('volvis.connected'))


class T07Tabs(unittest.TestCase):
    def test_tabs_are_independent(self):
        """Two tabs have a session each: rotating in one changes nothing in the other."""
        first = DRIVER.current_window_handle
        DRIVER.switch_to.new_window('tab')
        second = DRIVER.current_window_handle
        try:
            open_page()
            # the page's layout may still change after its first frame (the
            # panel filled in: a resize, a frame at the new size): wait
            # until no frame has come for a second
            end = time.monotonic() + WAIT_S
            n = js('volvis.frames')
            while time.monotonic() < end:
                time.sleep(1.0)
                m = js('volvis.frames')
                if m == n and js('volvis.lastFrame.sharp'):
                    break
                n = m
            idle = js('volvis.lastFrame')
            frames = js('volvis.frames')
            img_before = element_image('view3d')
            DRIVER.switch_to.window(first)
            seq = js('volvis.lastFrame.seq')
            drag_view(-150, 0)
            wait_sharp_after(seq, 'a sharp frame in the first tab')
            # one more round trip in the first tab: anything the second tab
            # would have got from the drag has been sent by now
            seq = js('volvis.lastFrame.seq')
            drag_view(20, 0, steps=2)
            wait_sharp_after(seq, 'a second sharp frame in the first tab')
            DRIVER.switch_to.window(second)
            self.assertEqual(js('volvis.lastFrame'), idle)
            self.assertEqual(js('volvis.frames'), frames)
            self.assertLess(mean_abs_diff(img_before, element_image('view3d')), 0.5)
            shot('07_second_tab')
        finally:
            DRIVER.switch_to.window(second)
            DRIVER.close()
            DRIVER.switch_to.window(first)


class T07Remote(unittest.TestCase):
    """Remote data: the URL and the prefix the server was given, by name; a prefix
    fills the URL field; a URL the server was not given is refused in one line."""

    def test_remote(self):
        def items():
            return [b.get_attribute('data-name') for b in
                    DRIVER.find_elements(By.CSS_SELECTOR, '#remote button')]
        wait_for('the remote data listed', lambda: REMOTE_URL in items())
        self.assertTrue(DRIVER.find_element(By.ID, 'remote-group').is_displayed())
        self.assertEqual(items(), [REMOTE_URL, REMOTE_PREFIX + '…'])
        click(DRIVER.find_element(By.CSS_SELECTOR, f'#remote button[data-name="{REMOTE_PREFIX}…"]'))
        field = DRIVER.find_element(By.ID, 'open-url')
        self.assertEqual(field.get_attribute('value'), REMOTE_PREFIX)
        self.assertEqual(js('document.activeElement.id'), 'open-url')
        name = js('volvis.state.name')
        msg = lambda: DRIVER.find_element(By.ID, 'status-msg')
        # a URL the server was not given: refused, one line in the status line
        field.clear()
        field.send_keys('http://127.0.0.1:9/elsewhere/x.ome.zarr')
        click(DRIVER.find_element(By.ID, 'open-url-button'))
        wait_for('the refusal', lambda: 'not a URL this server was given' in msg().text)
        self.assertIn('error', msg().get_attribute('class'))
        # a URL under the prefix, typed: the server tries it (nothing listens): one line
        field.clear()
        field.send_keys(REMOTE_PREFIX + 'x.ome.zarr' + Keys.ENTER)
        wait_for('the door\'s answer', lambda: 'x.ome.zarr' in msg().text and
                 'not a URL' not in msg().text and 'opening' not in msg().text)
        self.assertNotIn('\n', msg().text)
        self.assertEqual(js('volvis.state.name'), name)  # what was open stays open
        shot('07_remote')
        js('volvis.errors.length = 0')  # the two expected here; T08 counts its own


class T08Panel(unittest.TestCase):
    """The side panel against the real server; opens other files, so it runs last."""

    def click_file(self, name):
        click(DRIVER.find_element(By.CSS_SELECTOR, f'#files button[data-name="{name}"]'))

    def open_file(self, name):
        seq = js('volvis.lastFrame.seq')
        self.click_file(name)
        wait_for(f'{name} open', lambda: js('volvis.state.name') == name)
        return wait_sharp_after(seq, f'the first sharp frame of {name}')

    def changes_view(self, what, act, done, elem='view3d', least=1.0):
        """act() changes what `elem` shows (by a mean of more than `least` grey
        levels) once done() (the state the server sent back) holds."""
        before = element_image(elem)
        act()
        wait_for(f'the state after {what}', done)
        d = wait_for(f'{elem} to change with {what}', lambda: (
            lambda d: d if d > least else None)(mean_abs_diff(before, element_image(elem))))
        if elem == 'view3d':
            wait_for('a sharp frame', 'volvis.lastFrame.sharp')
        log(f'{what}: mean difference {d:.1f}')

    def test_panel(self):
        """Files (folders, ..), time steps, channels, presets, mode and window/level each do what they say."""
        names = lambda: [b.get_attribute('data-name') for b in
                         DRIVER.find_elements(By.CSS_SELECTOR, '#files button')]
        wait_for('the root listing', lambda: 'cells.nrrd' in names())
        self.assertEqual(names(), ['sub/', 'cells.nrrd', 'cells_scene.json', 'ct_head.nrrd'])
        self.click_file('sub/')
        # (sub holds the session T04 saved)
        wait_for('the folder sub', lambda: names()[:1] == ['..'] and 'cells.nrrd' not in names())
        self.assertTrue(DRIVER.find_element(By.ID, 'files-path').text.endswith('/sub/'))
        self.click_file('..')
        wait_for('the root again', lambda: 'cells.nrrd' in names())

        # time steps: a one-object file of three steps, one channel shown
        self.open_file('cells.nrrd')
        self.assertEqual(js('volvis.state.time_steps'), 3)
        self.assertTrue(DRIVER.find_element(By.ID, 'time').is_displayed())
        # channel controls only for more than one channel (the file's own, as the server shows them)
        self.assertEqual(DRIVER.find_element(By.ID, 'channels-group').is_displayed(),
                         len(js('volvis.state.channels')) > 1)
        self.changes_view('time step 3', lambda: DRIVER.find_element(By.ID, 'time').send_keys(Keys.END),
                          lambda: js('volvis.state.time') == 2)
        shot('08_time')

        # channels: the scene's three, by name, in their colours
        self.open_file('cells_scene.json')
        wait_for('the channel rows', lambda: DRIVER.find_element(By.ID, 'channels-group').is_displayed())
        self.assertFalse(DRIVER.find_element(By.ID, 'time').is_displayed())
        labels = [e.text for e in DRIVER.find_elements(By.CSS_SELECTOR, '#channels label')]
        self.assertEqual(labels, ['nuclei', 'membrane', 'protein'])
        for i, ch in enumerate(js('volvis.state.channels')):
            self.assertEqual(DRIVER.find_element(By.ID, f'channel-{i}-color').get_attribute('value'),
                             ch['color'].lower())
        # (the slices blend the channels; this scene's default camera shows the
        # 32-voxel volume small in the 3-D view)
        self.changes_view('hiding a channel',
                          lambda: click(DRIVER.find_element(By.ID, 'channel-1-visible')),
                          lambda: js('volvis.state.channels[1].visible') is False, elem='slice-axial')
        # a colour picker cannot be typed into: set it as the picker does
        js('(e => { e.value = "#ffff00"; e.dispatchEvent(new Event("change")); })'
           '(document.getElementById("channel-0-color"))')
        wait_for('the new colour', lambda: js('volvis.state.channels[0].color') == '#ffff00')
        shot('08_channels')

        # presets, mode and isovalue on the CT head
        self.open_file('ct_head.nrrd')
        self.assertFalse(DRIVER.find_element(By.ID, 'channels-group').is_displayed())
        self.assertFalse(DRIVER.find_element(By.ID, 'time-group').is_displayed())
        self.changes_view('preset ct-skin',
                          lambda: click(DRIVER.find_element(By.ID, 'preset-ct-skin')),
                          lambda: js('volvis.state.preset') == 'ct-skin')
        self.assertEqual(DRIVER.find_element(By.ID, 'preset-ct-skin').get_attribute('aria-pressed'), 'true')
        self.assertFalse(DRIVER.find_element(By.ID, 'isovalue').is_displayed())
        self.changes_view('mode MIP', lambda: Select(DRIVER.find_element(By.ID, 'mode')).select_by_value('mip'),
                          lambda: js('volvis.state.mode') == 'mip')
        isovalue = js('volvis.state.isovalue')
        self.changes_view('mode iso', lambda: Select(DRIVER.find_element(By.ID, 'mode')).select_by_value('iso'),
                          lambda: js('volvis.state.mode') == 'iso')
        self.assertTrue(DRIVER.find_element(By.ID, 'isovalue').is_displayed())
        self.assertEqual(js('volvis.state.isovalue'), isovalue, 'choosing the mode changed the isovalue')

        def set_isovalue():
            field = DRIVER.find_element(By.ID, 'isovalue')
            field.clear()
            field.send_keys('500', Keys.TAB)
        self.changes_view('isovalue 500', set_isovalue, lambda: js('volvis.state.isovalue') == 500)
        shot('08_iso')

        # window/level: a narrow window on soft tissue changes every slice
        def window_level():
            for field, value in (('window', '80'), ('level', '40')):
                f = DRIVER.find_element(By.ID, field)
                f.clear()
                f.send_keys(value, Keys.TAB)
        self.changes_view('window 80, level 40', window_level,
                          lambda: DRIVER.find_element(By.ID, 'level').get_attribute('value') == '40',
                          elem='slice-axial', least=5.0)
        shot('08_window_level')
        self.assertEqual(js('volvis.errors'), [])


if __name__ == '__main__':
    os.makedirs(OUT, exist_ok=True)
    result = unittest.main(argv=[sys.argv[0], '-v'], exit=False).result
    sys.exit(0 if result.wasSuccessful() else 1)
