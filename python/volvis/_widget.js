// The page side of volvis.widgets.View (anywidget ES module; docs/python.md,
// "The Jupyter widget"). It draws the kernel's frames (JPEG bytes in a
// custom message's buffer) into a canvas and turns pointer, touch, wheel and
// keys into "motion" messages, as web/js/view3d.js does for `volvis serve`:
// deltas in pixels of the frame, gathered and sent at most once an animation
// frame while a gesture goes on, then one "end" (the kernel then draws the
// full-quality frame). A frame is drawn only when it is newer than the one
// on screen (decoding is asynchronous: a late older frame is dropped).

// A wheel burst or a key repeat ends after this long without input.
const BURST_END_MS = 150;
// Zoom factor per 100 px of wheel deltaY (1.1 = 10 % closer per notch).
const WHEEL_BASE = 1.1;
// Deltas of one arrow-key press, in pixels.
const KEY_STEP = 12;
// What one motion may carry (vv_nav_apply clamps beyond): more waits for the next.
const MAX_PIXELS = 4096;
const MAX_FACTOR = 16;
const AXES = ['axial', 'coronal', 'sagittal'];

const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));

function el(tag, attrs = {}, parent = null) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'text') e.textContent = v;
    else e.setAttribute(k, v);
  }
  if (parent) parent.appendChild(e);
  return e;
}

function render({ model, el: host }) {
  const root = el('div', { class: 'volvis-widget' }, host);
  const bar = el('div', { class: 'volvis-bar', role: 'toolbar', 'aria-label': 'VolVis view controls' }, root);

  const modeSel = el('select', { 'aria-label': 'Rendering mode', class: 'volvis-mode' }, bar);
  const presetSel = el('select', { 'aria-label': 'Transfer function preset', class: 'volvis-preset' }, bar);
  const slicesBox = el('label', { class: 'volvis-slices-toggle' }, bar);
  const slicesChk = el('input', { type: 'checkbox', 'aria-label': 'Show slice views' }, slicesBox);
  slicesBox.appendChild(document.createTextNode(' slices'));
  const status = el('span', { class: 'volvis-status', role: 'status', 'aria-live': 'polite' }, bar);

  const main = el('div', { class: 'volvis-main' }, root);
  const canvas = el('canvas', {
    class: 'volvis-canvas', tabindex: '0', role: 'img',
    'aria-label': 'VolVis 3-D view: drag to rotate, shift-drag to pan, wheel or pinch to zoom, arrow keys rotate, + and - zoom',
  }, main);
  const ctx = canvas.getContext('2d', { alpha: false });
  const sliceBox = el('div', { class: 'volvis-slices' }, main);
  const sliceViews = {};
  for (const a of AXES) {
    const fig = el('figure', { class: 'volvis-slice' }, sliceBox);
    const c = el('canvas', { role: 'img', 'aria-label': `${a} slice`, class: 'volvis-slice-canvas' }, fig);
    const cap = el('figcaption', {}, fig);
    const range = el('input', { type: 'range', min: '0', max: '0', step: '1', 'aria-label': `${a} slice index` }, cap);
    const label = el('span', { text: a }, cap);
    range.addEventListener('input', () => {
      model.send({ type: 'slice', axis: a, index: Number(range.value) });
    });
    sliceViews[a] = { canvas: c, ctx: c.getContext('2d', { alpha: false }), range, label, seq: 0 };
  }

  // ---- controls <-> traits ----
  function fillSelect(sel, names, value, empty) {
    sel.textContent = '';
    if (empty) el('option', { value: '', text: empty }, sel);
    for (const n of names) el('option', { value: n, text: n }, sel);
    sel.value = value;
  }
  const syncControls = () => {
    fillSelect(modeSel, model.get('modes'), model.get('mode'), null);
    fillSelect(presetSel, model.get('presets'), model.get('preset'), '(own transfer function)');
    slicesChk.checked = model.get('slices');
    sliceBox.hidden = !model.get('slices');
    const counts = model.get('slice_count') || {};
    for (const a of AXES) sliceViews[a].range.max = String(Math.max(0, (counts[a] || 1) - 1));
  };
  syncControls();
  const onSize = () => {
    canvas.style.aspectRatio = `${model.get('width')} / ${model.get('height')}`;
    canvas.style.width = `${model.get('width')}px`;
  };
  onSize();
  modeSel.addEventListener('change', () => { model.set('mode', modeSel.value); model.save_changes(); });
  presetSel.addEventListener('change', () => { model.set('preset', presetSel.value); model.save_changes(); });
  slicesChk.addEventListener('change', () => { model.set('slices', slicesChk.checked); model.save_changes(); });
  const traitHandlers = [
    ['change:mode', syncControls], ['change:preset', syncControls], ['change:slices', syncControls],
    ['change:slice_count', syncControls], ['change:width', onSize], ['change:height', onSize],
    ['change:status', () => { status.textContent = model.get('status'); }],
  ];
  for (const [ev, f] of traitHandlers) model.on(ev, f);

  // ---- frames ----
  let shown = 0;      // seq of the frame on screen
  let decoding = 0;   // frames being decoded
  async function drawFrame(msg, buffers, target) {
    const blob = new Blob([buffers[0]], { type: msg.mime || 'image/jpeg' });
    let bm;
    try {
      bm = await createImageBitmap(blob);
    } catch (e) {
      status.textContent = `frame ${msg.seq}: cannot decode (${e})`;
      return;
    }
    if (target === null) {
      if (msg.seq <= shown) { bm.close(); return; } // a newer one is on screen
      shown = msg.seq;
      // a reduced frame is drawn scaled up to the view's size
      if (canvas.width !== msg.view_width || canvas.height !== msg.view_height) {
        canvas.width = msg.view_width;
        canvas.height = msg.view_height;
      }
      ctx.imageSmoothingEnabled = true;
      ctx.drawImage(bm, 0, 0, canvas.width, canvas.height);
      canvas.dataset.seq = String(msg.seq);
      canvas.dataset.kind = msg.kind;
      canvas.dataset.sharp = msg.sharp ? '1' : '0';
      root.dataset.frames = String((Number(root.dataset.frames) || 0) + 1);
    } else {
      const v = sliceViews[target];
      v.canvas.width = msg.width;
      v.canvas.height = msg.height;
      v.ctx.drawImage(bm, 0, 0);
      v.range.max = String(msg.count - 1);
      v.range.value = String(msg.index);
      v.label.textContent = `${target} ${msg.index + 1}/${msg.count}`;
    }
    bm.close();
  }
  const onMsg = (msg, buffers) => {
    if (!msg || !buffers || !buffers.length) return;
    if (msg.type === 'frame') drawFrame(msg, buffers, null);
    else if (msg.type === 'slice' && sliceViews[msg.axis]) drawFrame(msg, buffers, msg.axis);
  };
  model.on('msg:custom', onMsg);

  // ---- input ----
  const pending = new Map(); // motion -> {dx, dy, factor}
  let raf = 0;
  let gesture = 0;           // gestures going on (drag, touch, wheel or key burst)
  let burstTimer = 0;
  const scale = () => {
    const r = canvas.getBoundingClientRect();
    return r.width > 0 ? model.get('width') / r.width : 1;
  };
  function flush() {
    raf = 0;
    for (const [motion, p] of pending) {
      const dx = clamp(p.dx, -MAX_PIXELS, MAX_PIXELS);
      const dy = clamp(p.dy, -MAX_PIXELS, MAX_PIXELS);
      const factor = clamp(p.factor, 1 / MAX_FACTOR, MAX_FACTOR);
      if (motion === 'zoom' ? factor !== 1 : dx !== 0 || dy !== 0) {
        model.send({ type: 'motion', motion, dx, dy, factor });
        root.dataset.motions = String((Number(root.dataset.motions) || 0) + 1);
      }
    }
    pending.clear();
  }
  function add(motion, dx, dy, factor = 1) {
    const s = scale();
    const p = pending.get(motion) || { dx: 0, dy: 0, factor: 1 };
    p.dx += dx * s;
    p.dy += dy * s;
    p.factor *= factor;
    pending.set(motion, p);
    if (!raf) raf = requestAnimationFrame(flush);
  }
  function end() {
    if (raf) { cancelAnimationFrame(raf); flush(); }
    model.send({ type: 'end' });
  }
  function burst(motion, dx, dy, factor) {
    add(motion, dx, dy, factor);
    clearTimeout(burstTimer);
    burstTimer = setTimeout(end, BURST_END_MS);
  }

  const pointers = new Map(); // pointerId -> {x, y, motion}
  const onDown = (e) => {
    let motion = 'rotate';
    if (e.pointerType !== 'touch') {
      if (e.button === 0) motion = e.shiftKey ? 'pan' : 'rotate';
      else if (e.button === 1 || e.button === 2) motion = 'pan';
      else return;
    }
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY, motion });
    canvas.setPointerCapture(e.pointerId);
    canvas.focus({ preventScroll: true });
    e.preventDefault();
  };
  // One pointer rotates (pans with shift or the middle/right button); two
  // touches pinch (zoom by the ratio of their distances) and pan by half of
  // one finger's motion (their midpoint's).
  const onMove = (e) => {
    const t = pointers.get(e.pointerId);
    if (!t) return;
    if (pointers.size === 1) {
      add(t.motion, e.clientX - t.x, e.clientY - t.y);
    } else {
      const other = [...pointers.entries()].find(([id]) => id !== e.pointerId)[1];
      const before = Math.hypot(t.x - other.x, t.y - other.y);
      const after = Math.hypot(e.clientX - other.x, e.clientY - other.y);
      if (before > 4 && after > 4) add('zoom', 0, 0, after / before);
      add('pan', (e.clientX - t.x) / 2, (e.clientY - t.y) / 2);
    }
    t.x = e.clientX;
    t.y = e.clientY;
  };
  const onUp = (e) => {
    if (!pointers.delete(e.pointerId)) return;
    if (pointers.size === 0) end();
  };
  const onWheel = (e) => {
    e.preventDefault(); // not passive: the notebook must not scroll
    let dy = e.deltaY;
    if (e.deltaMode === WheelEvent.DOM_DELTA_LINE) dy *= 40;
    else if (e.deltaMode === WheelEvent.DOM_DELTA_PAGE) dy *= 800;
    if (dy !== 0) burst('zoom', 0, 0, WHEEL_BASE ** (-dy / 100));
  };
  const onKey = (e) => {
    if (e.altKey || e.ctrlKey || e.metaKey) return;
    const motion = e.shiftKey ? 'pan' : 'rotate';
    const arrows = {
      ArrowLeft: [-KEY_STEP, 0], ArrowRight: [KEY_STEP, 0],
      ArrowUp: [0, -KEY_STEP], ArrowDown: [0, KEY_STEP],
    };
    if (arrows[e.key]) burst(motion, arrows[e.key][0] / scale(), arrows[e.key][1] / scale(), 1);
    else if (e.key === '+' || e.key === '=') burst('zoom', 0, 0, WHEEL_BASE);
    else if (e.key === '-' || e.key === '_') burst('zoom', 0, 0, 1 / WHEEL_BASE);
    else return;
    e.preventDefault();
    e.stopPropagation(); // JupyterLab's own shortcuts must not see it
  };
  const listeners = [
    ['pointerdown', onDown], ['pointermove', onMove], ['pointerup', onUp],
    ['pointercancel', onUp], ['contextmenu', (e) => e.preventDefault()], ['keydown', onKey],
  ];
  for (const [ev, f] of listeners) canvas.addEventListener(ev, f);
  canvas.addEventListener('wheel', onWheel, { passive: false });

  model.send({ type: 'ready' }); // the newest frame and slices, for this view
  return () => {
    for (const [ev, f] of listeners) canvas.removeEventListener(ev, f);
    canvas.removeEventListener('wheel', onWheel);
    for (const [ev, f] of traitHandlers) model.off(ev, f);
    model.off('msg:custom', onMsg);
    clearTimeout(burstTimer);
    if (raf) cancelAnimationFrame(raf);
  };
}

export default { render };
