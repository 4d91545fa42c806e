// The three slice views (axial, coronal, sagittal): SLCE images, the value
// under the pointer (probe), window/level shared by all three, and a linked
// cursor drawn as crosshairs.
//
// The client does not know how the server lays a slice out (orientation,
// flips, the fit of the volume into the image). It learns it instead: four
// probes per view and image size give the affine map from (x, y, slice
// index) to the voxel (i, j, k), whose inverse places the cursor in every
// view and picks the slice index through it.

import { clamp, fitRect, formatNumber } from './util.js';

export const AXES = ['axial', 'coronal', 'sagittal'];
// The voxel axis each view steps through, used only until the view's map is
// learnt (true for volumes whose index axes are the anatomical ones).
const FALLBACK_NORMAL = { axial: 2, coronal: 1, sagittal: 0 };
// A request with no answer after this long (an `error` instead) is given up.
const REQUEST_TIMEOUT_MS = 5000;
const COLORS = { axial: '#e0524d', coronal: '#62b45d', sagittal: '#e6cc4a' };

// ---- 3-vector helpers for the learnt maps ----
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

/**
 * The affine map ijk = A + B x + C y + D index of one view and image size,
 * with the rows of the inverse of the matrix [B C D].
 */
class SliceMap {
  constructor(A, B, C, D) {
    this.A = A;
    this.B = B;
    this.C = C;
    // A single slice gives no D: step one voxel along the plane's normal.
    const n = cross(B, C);
    const len = Math.hypot(...n);
    if (Math.hypot(...D) < 1e-9 && len > 0) D = scale(n, 1 / len);
    this.D = D;
    const det = dot(B, cross(C, D));
    if (!Number.isFinite(det) || Math.abs(det) < 1e-12) throw new Error('degenerate slice map');
    // rows of [B C D]^-1
    this.inv = [scale(cross(C, D), 1 / det), scale(cross(D, B), 1 / det), scale(cross(B, C), 1 / det)];
  }

  /** (x, y, index) of voxel position ijk. */
  fromIjk(ijk) {
    const r = sub(ijk, this.A);
    return { x: dot(this.inv[0], r), y: dot(this.inv[1], r), index: dot(this.inv[2], r) };
  }

  toIjk(x, y, index) {
    return [0, 1, 2].map((c) => this.A[c] + this.B[c] * x + this.C[c] * y + this.D[c] * index);
  }
}

class SliceView {
  constructor(axis, group) {
    this.axis = axis;
    this.group = group;
    this.canvas = document.getElementById(`slice-${axis}`);
    this.overlay = document.getElementById(`slice-${axis}-overlay`);
    this.slider = document.getElementById(`slice-${axis}-index`);
    this.indexOut = document.getElementById(`slice-${axis}-index-value`);
    this.probeText = document.getElementById(`probe-${axis}`);
    this.ctx = this.canvas.getContext('2d', { alpha: false });
    this.octx = this.overlay.getContext('2d');

    this.count = 0; // slices along this axis
    this.index = 0;
    this.size = null; // {width, height} of the images asked for (device pixels)

    this.slice = { busy: null, timer: 0 }; // the request in flight (its key)
    this.image = null; // {bitmap, header, rect} on screen
    this.decoding = null;

    this.probe = { busy: false, timer: 0, next: null }; // pointer probes: one in flight
    this.queue = []; // probes sent, in order, awaiting replies
    this.maps = new Map(); // "WxH" -> SliceMap | 'pending' | 'failed'
    this.calib = null; // replies collected for the map being learnt

    this.wl = null; // right-drag window/level: the start
    this.bind();
  }

  get sizeKey() {
    return this.size ? `${this.size.width}x${this.size.height}` : '';
  }

  get map() {
    const m = this.maps.get(this.sizeKey);
    return m instanceof SliceMap ? m : null;
  }

  // ---- state ----

  /** A new data set (or a new number of slices): the middle slice. */
  reset(count) {
    this.count = count;
    this.index = Math.floor((count - 1) / 2);
    this.slider.max = String(Math.max(0, count - 1));
    this.slider.value = String(this.index);
    this.indexOut.value = this.indexLabel();
    this.maps.clear();
    this.image?.bitmap.close();
    this.image = null;
    this.probeText.textContent = '–';
    this.probeText.classList.remove('has-value');
    this.draw();
  }

  indexLabel() {
    return this.count ? `${this.index + 1}/${this.count}` : '–';
  }

  setIndex(index, fromUser = true) {
    index = clamp(Math.round(index), 0, Math.max(0, this.count - 1));
    if (index === this.index) return;
    const map = this.map;
    const cursor = this.group.cursor;
    this.index = index;
    this.slider.value = String(index);
    this.indexOut.value = this.indexLabel();
    // Stepping through slices carries the cursor along this view's normal,
    // so that the other views' crosshairs follow the slice shown here.
    if (fromUser && cursor && map) {
      const p = map.fromIjk(cursor);
      this.group.setCursor(map.toIjk(p.x, p.y, index).map(Math.round), this.axis);
    }
    this.request();
  }

  // ---- slice images ----

  /** Asks for the slice as it should be now; one request in flight per view. */
  request() {
    const g = this.group;
    if (!this.size || !this.count || !g.conn.open) return;
    const msg = {
      type: 'slice', axis: this.axis, index: this.index,
      width: this.size.width, height: this.size.height,
    };
    if (g.wl) {
      msg.window = g.wl.window;
      msg.level = g.wl.level;
    }
    const key = JSON.stringify([msg, g.generation]);
    if (this.slice.busy) {
      this.slice.want = key; // sent when the one in flight is answered
      return;
    }
    if (key === this.slice.shown) return;
    this.slice.busy = key;
    this.slice.want = null;
    g.conn.send(msg);
    clearTimeout(this.slice.timer);
    this.slice.timer = setTimeout(() => this.sliceDone(), REQUEST_TIMEOUT_MS);
  }

  sliceDone() {
    clearTimeout(this.slice.timer);
    this.slice.busy = null;
    if (this.slice.want) this.request();
  }

  onSlice(header, payload) {
    this.slice.shown = this.slice.busy;
    this.sliceDone();
    if (Number.isInteger(header.count) && header.count > 0 && header.count !== this.count) {
      this.count = header.count;
      this.slider.max = String(header.count - 1);
      this.indexOut.value = this.indexLabel();
    }
    if (header.index !== this.index) return; // the slider has moved on
    const blob = new Blob([payload], { type: 'image/jpeg' });
    const token = {};
    this.decoding = token;
    createImageBitmap(blob).then((bitmap) => {
      if (this.decoding !== token) {
        bitmap.close(); // a newer slice came while this one decoded
        return;
      }
      this.image?.bitmap.close();
      this.image = { bitmap, header };
      this.draw();
      this.learnMap();
    }, (err) => this.group.hooks.onError(`${this.axis} slice could not be decoded: ${err.message}`));
    if (this.group.wl === null && Number.isFinite(header.window)) {
      this.group.showWl(header.window, header.level);
    }
  }

  /** The view's size changed: images of the new size. */
  resized(width, height) {
    const dpr = window.devicePixelRatio || 1;
    const w = clamp(Math.round(width * dpr), 16, 2048);
    const h = clamp(Math.round(height * dpr), 16, 2048);
    for (const c of [this.canvas, this.overlay]) {
      c.width = w;
      c.height = h;
    }
    this.draw();
    if (this.size && this.size.width === w && this.size.height === h) return;
    this.size = { width: w, height: h };
    this.request();
  }

  draw() {
    const { ctx, canvas } = this;
    ctx.fillStyle = '#000';
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    if (this.image) {
      const bm = this.image.bitmap;
      const r = fitRect(bm.width, bm.height, canvas.width, canvas.height);
      this.image.rect = r;
      ctx.imageSmoothingEnabled = true;
      ctx.drawImage(bm, r.x, r.y, r.w, r.h);
    }
    this.drawOverlay();
  }

  /** Crosshairs through the cursor, in the colours of the other two planes, and the edge labels. */
  drawOverlay() {
    const { octx: ctx, overlay } = this;
    ctx.clearRect(0, 0, overlay.width, overlay.height);
    const img = this.image;
    if (!img) return;
    const r = img.rect;
    const sx = r.w / (this.size?.width ?? img.bitmap.width);
    const sy = r.h / (this.size?.height ?? img.bitmap.height);

    const edges = img.header.edges;
    if (Array.isArray(edges) && edges.length === 4) {
      ctx.font = `${Math.round(12 * (window.devicePixelRatio || 1))}px system-ui, sans-serif`;
      ctx.fillStyle = 'rgba(220, 228, 238, 0.8)';
      const pad = 4;
      ctx.textBaseline = 'middle';
      ctx.textAlign = 'right';
      ctx.fillText(edges[0], overlay.width - pad, overlay.height / 2);
      ctx.textAlign = 'left';
      ctx.fillText(edges[1], pad, overlay.height / 2);
      ctx.textAlign = 'center';
      ctx.textBaseline = 'top';
      ctx.fillText(edges[2], overlay.width / 2, pad);
      ctx.textBaseline = 'bottom';
      ctx.fillText(edges[3], overlay.width / 2, overlay.height - pad);
    }

    const cursor = this.group.cursor;
    const map = this.map;
    if (!cursor) return;
    let p;
    if (map) {
      p = map.fromIjk(cursor);
    } else if (this.group.cursorPixel && this.group.cursorPixel.axis === this.axis) {
      p = this.group.cursorPixel; // the view clicked, before its map is known
    } else {
      return;
    }
    const cx = r.x + p.x * sx;
    const cy = r.y + p.y * sy;
    const gap = 6 * (window.devicePixelRatio || 1);
    const lines = this.crosshairColors();
    ctx.lineWidth = Math.max(1, window.devicePixelRatio || 1);
    ctx.globalAlpha = 0.85;
    ctx.strokeStyle = lines.vertical;
    ctx.beginPath();
    ctx.moveTo(cx + 0.5, r.y);
    ctx.lineTo(cx + 0.5, cy - gap);
    ctx.moveTo(cx + 0.5, cy + gap);
    ctx.lineTo(cx + 0.5, r.y + r.h);
    ctx.stroke();
    ctx.strokeStyle = lines.horizontal;
    ctx.beginPath();
    ctx.moveTo(r.x, cy + 0.5);
    ctx.lineTo(cx - gap, cy + 0.5);
    ctx.moveTo(cx + gap, cy + 0.5);
    ctx.lineTo(r.x + r.w, cy + 0.5);
    ctx.stroke();
    ctx.globalAlpha = 1;
  }

  /**
   * Which other plane each crosshair line is: the vertical line is the
   * plane whose slice index changes along this image's x.
   */
  crosshairColors() {
    const fallback = { vertical: '#cfd6df', horizontal: '#cfd6df' };
    const map = this.map;
    if (!map) return fallback;
    const others = AXES.filter((a) => a !== this.axis).map((a) => this.group.views[a]);
    const along = others.map((v) => {
      const m = v.map;
      if (!m) return null;
      const row = m.inv[2]; // d(index)/d(ijk)
      return { axis: v.axis, gx: Math.abs(dot(row, map.B)), gy: Math.abs(dot(row, map.C)) };
    });
    if (along.some((a) => a === null)) return fallback;
    const [a, b] = along;
    const verticalIsA = a.gx / (a.gy + 1e-9) >= b.gx / (b.gy + 1e-9);
    return verticalIsA
      ? { vertical: COLORS[a.axis], horizontal: COLORS[b.axis] }
      : { vertical: COLORS[b.axis], horizontal: COLORS[a.axis] };
  }

  // ---- probes ----

  sendProbe(x, y, purpose, index = this.index) {
    const msg = {
      type: 'probe', axis: this.axis, index, x, y,
      width: this.size.width, height: this.size.height,
    };
    if (!this.group.conn.send(msg)) return false;
    this.queue.push({ x, y, index, purpose, key: this.sizeKey });
    return true;
  }

  /** A pointer probe: at most one in flight; the newest position waits. */
  pointerProbe(x, y, setCursor) {
    const next = { x, y, setCursor };
    if (this.probe.busy) {
      // a click must not be lost to a later hover
      if (!this.probe.next?.setCursor || setCursor) this.probe.next = next;
      return;
    }
    if (!this.sendProbe(x, y, setCursor ? 'cursor' : 'hover')) return;
    this.probe.busy = true;
    clearTimeout(this.probe.timer);
    this.probe.timer = setTimeout(() => this.pointerProbeDone(), REQUEST_TIMEOUT_MS);
  }

  pointerProbeDone() {
    clearTimeout(this.probe.timer);
    this.probe.busy = false;
    const next = this.probe.next;
    this.probe.next = null;
    if (next) this.pointerProbe(next.x, next.y, next.setCursor);
  }

  onProbe(msg) {
    // Replies come in the order asked; match on x, y in case one was lost.
    let i = this.queue.findIndex((q) => q.x === msg.x && q.y === msg.y);
    if (i < 0) i = 0;
    const [req] = this.queue.splice(0, i + 1).slice(-1);
    if (!req) return;
    if (req.purpose === 'calib') {
      this.calibReply(req, msg);
      return;
    }
    this.showProbe(msg);
    this.group.hooks.onProbe?.(msg);
    if (req.purpose === 'cursor' && typeof msg.value === 'number' && Array.isArray(msg.ijk)) {
      this.group.cursorPixel = { axis: this.axis, x: req.x, y: req.y };
      this.group.setCursor(msg.ijk.map(Math.round), this.axis, msg.indices);
    }
    this.pointerProbeDone();
  }

  showProbe(msg) {
    const t = this.probeText;
    if (typeof msg.value !== 'number' || !Array.isArray(msg.ijk)) {
      t.textContent = 'outside the volume';
      t.classList.remove('has-value');
      return;
    }
    const unit = msg.value_unit ? ` ${msg.value_unit}` : '';
    const ijk = msg.ijk.map((v) => Math.round(v)).join(', ');
    t.textContent = `${formatNumber(msg.value)}${unit} at (${ijk})`;
    t.classList.add('has-value');
    const world = Array.isArray(msg.world) ? msg.world.map(formatNumber).join(', ') : '';
    t.title = world ? `world (${world}) ${msg.unit ?? ''}` : '';
  }

  /**
   * Learns this view's map for the current image size: probes at the
   * image's centre, a step right, a step down, and the centre one slice
   * further (only ijk is used; the value may be outside, i.e. null).
   */
  learnMap() {
    const key = this.sizeKey;
    if (!key || this.maps.has(key) || !this.count) return;
    const { width, height } = this.size;
    const d = Math.max(4, Math.floor(Math.min(width, height) / 8));
    const cx = Math.floor(width / 2) + 0.5;
    const cy = Math.floor(height / 2) + 0.5;
    const i0 = this.index;
    const i1 = i0 + 1 < this.count ? i0 + 1 : Math.max(0, i0 - 1);
    this.maps.set(key, 'pending');
    this.calib = { key, d, cx, cy, i0, i1, got: [] };
    const points = [[cx, cy, i0], [cx + d, cy, i0], [cx, cy + d, i0], [cx, cy, i1]];
    for (const [x, y, index] of points) this.sendProbe(x, y, 'calib', index);
  }

  calibReply(req, msg) {
    const c = this.calib;
    if (!c || req.key !== c.key) return;
    const ok = Array.isArray(msg.ijk) && msg.ijk.length === 3 && msg.ijk.every(Number.isFinite);
    if (!ok) {
      this.maps.set(c.key, 'failed');
      this.calib = null;
      return;
    }
    c.got.push(msg.ijk);
    if (c.got.length < 4) return;
    const [p0, p1, p2, p3] = c.got;
    const B = scale(sub(p1, p0), 1 / c.d);
    const C = scale(sub(p2, p0), 1 / c.d);
    const D = c.i1 === c.i0 ? [0, 0, 0] : scale(sub(p3, p0), 1 / (c.i1 - c.i0));
    const A = [0, 1, 2].map((k) => p0[k] - B[k] * c.cx - C[k] * c.cy - D[k] * c.i0);
    try {
      this.maps.set(c.key, new SliceMap(A, B, C, D));
    } catch (err) {
      this.maps.set(c.key, 'failed');
      console.warn(`volvis: ${this.axis}: ${err.message}`);
    }
    this.calib = null;
    this.group.redrawOverlays();
  }

  /** Slice index of this view through voxel ijk. */
  indexThrough(ijk) {
    const map = this.map;
    if (map) return map.fromIjk(ijk).index;
    return ijk[FALLBACK_NORMAL[this.axis]];
  }

  // ---- pointer ----

  /**
   * The point of the slice image under the pointer, in the image's pixels
   * (continuous: pixel (i, j) covers i..i+1, j..j+1, as the server's
   * vv_slice_plane_to_world takes it), or null off the image. Rounded to
   * 1/8 pixel so that it comes back in the reply exactly as sent.
   */
  imagePoint(e) {
    const img = this.image;
    if (!img?.rect || !this.size) return null;
    const box = this.canvas.getBoundingClientRect();
    const bx = ((e.clientX - box.left) / box.width) * this.canvas.width;
    const by = ((e.clientY - box.top) / box.height) * this.canvas.height;
    // in the coordinates of the image asked for (the one on screen may be
    // of the size before a resize, and is scaled to the view)
    const x = ((bx - img.rect.x) / img.rect.w) * this.size.width;
    const y = ((by - img.rect.y) / img.rect.h) * this.size.height;
    if (!(x >= 0 && y >= 0 && x < this.size.width && y < this.size.height)) return null;
    return { x: Math.round(x * 8) / 8, y: Math.round(y * 8) / 8 };
  }

  bind() {
    const c = this.canvas;
    c.addEventListener('contextmenu', (e) => e.preventDefault());
    c.addEventListener('pointerdown', (e) => {
      if (e.button === 2) {
        const g = this.group;
        const cur = g.currentWl();
        if (!cur) return;
        this.wl = { id: e.pointerId, x: e.clientX, y: e.clientY, ...cur };
      } else if (e.button === 0) {
        this.cursorDrag = e.pointerId;
        const p = this.imagePoint(e);
        if (p) this.pointerProbe(p.x, p.y, true);
      } else {
        return;
      }
      c.setPointerCapture(e.pointerId);
      e.preventDefault();
    });
    c.addEventListener('pointermove', (e) => {
      if (this.wl && e.pointerId === this.wl.id) {
        // Window widens to the right, level rises downwards; a full range per 1000 px.
        const [lo, hi] = this.group.range ?? [0, 1000];
        const k = Math.max(hi - lo, 1e-6) / 1000;
        const w = Math.max(k, this.wl.window + (e.clientX - this.wl.x) * k);
        this.group.setWl(w, this.wl.level + (e.clientY - this.wl.y) * k);
        return;
      }
      const p = this.imagePoint(e);
      if (p) this.pointerProbe(p.x, p.y, this.cursorDrag === e.pointerId);
    });
    const up = (e) => {
      if (this.wl && e.pointerId === this.wl.id) this.wl = null;
      if (this.cursorDrag === e.pointerId) this.cursorDrag = null;
    };
    c.addEventListener('pointerup', up);
    c.addEventListener('pointercancel', up);
    c.addEventListener('pointerleave', () => {
      if (!this.probe.busy) this.probeText.classList.remove('has-value');
    });
    c.addEventListener('wheel', (e) => {
      e.preventDefault();
      if (e.deltaY) this.setIndex(this.index + (e.deltaY > 0 ? -1 : 1));
    }, { passive: false });
    this.slider.addEventListener('input', () => this.setIndex(Number(this.slider.value)));
    new ResizeObserver((entries) => {
      const box = entries[entries.length - 1].contentRect;
      if (box.width > 0 && box.height > 0) this.resized(box.width, box.height);
    }).observe(c);
  }
}

/** The three views together: the data set, window/level and the cursor. */
export class SliceViews {
  /** hooks: {onError(text), onProbe(reply): a reply to a probe of the pointer (not the learning ones)} */
  constructor(conn, hooks) {
    this.conn = conn;
    this.hooks = hooks;
    this.views = {};
    this.cursor = null; // [i, j, k] voxel
    this.cursorPixel = null; // {axis, x, y} of the last click
    this.wl = null; // {window, level} set by the user; null: the server's auto window
    this.auto = null;
    this.range = null;
    this.dataKey = null;
    this.generation = 0; // grows when the data shown changes (file, time step)
    this.windowInput = document.getElementById('window');
    this.levelInput = document.getElementById('level');
    for (const axis of AXES) this.views[axis] = new SliceView(axis, this);

    const fromInputs = () => {
      const w = Number(this.windowInput.value);
      const l = Number(this.levelInput.value);
      if (this.windowInput.value !== '' && this.levelInput.value !== '' &&
          Number.isFinite(w) && Number.isFinite(l) && w > 0) this.setWl(w, l);
    };
    this.windowInput.addEventListener('change', fromInputs);
    this.levelInput.addEventListener('change', fromInputs);
    document.getElementById('wl-auto').addEventListener('click', () => {
      this.wl = null;
      if (this.auto) this.showWl(this.auto.window, this.auto.level);
      this.requestAll();
    });
  }

  onState(s) {
    this.range = Array.isArray(s.range) ? s.range : null;
    if (Number.isFinite(s.window)) this.auto = { window: s.window, level: s.level };
    const key = JSON.stringify([s.name, s.dims, s.slices]);
    const dataKey = JSON.stringify([key, s.time, s.channels]);
    if (dataKey === this.dataKey) return;
    const newData = !this.dataKey || key !== JSON.parse(this.dataKey)[0];
    this.dataKey = dataKey;
    this.generation++;
    if (newData) {
      this.cursor = null;
      this.cursorPixel = null;
      this.wl = null;
      if (this.auto) this.showWl(this.auto.window, this.auto.level);
      for (const axis of AXES) this.views[axis].reset(s.slices?.[axis] ?? 0);
    }
    this.requestAll();
  }

  requestAll() {
    for (const axis of AXES) this.views[axis].request();
  }

  /** The socket is open again or for the first time: ask for what is on screen. */
  onOpen() {
    this.requestAll();
  }

  onSlice(header, payload) {
    this.views[header.axis]?.onSlice(header, payload);
  }

  onProbe(msg) {
    this.views[msg.axis]?.onProbe(msg);
  }

  currentWl() {
    if (this.wl) return this.wl;
    const w = Number(this.windowInput.value);
    const l = Number(this.levelInput.value);
    if (Number.isFinite(w) && Number.isFinite(l) && w > 0) return { window: w, level: l };
    return this.auto;
  }

  showWl(window, level) {
    if (document.activeElement !== this.windowInput) this.windowInput.value = formatNumber(window);
    if (document.activeElement !== this.levelInput) this.levelInput.value = formatNumber(level);
  }

  setWl(window, level) {
    this.wl = { window, level };
    this.showWl(window, level);
    this.requestAll();
  }

  /**
   * The linked cursor moved to voxel ijk (from view `from`): the other
   * views go through it, at the slice `indices` of the probe reply when
   * given (the server's own), else through the learnt maps.
   */
  setCursor(ijk, from, indices = null) {
    this.cursor = ijk;
    for (const axis of AXES) {
      if (axis === from) continue;
      const v = this.views[axis];
      v.setIndex(Number.isInteger(indices?.[axis]) ? indices[axis] : v.indexThrough(ijk), false);
    }
    this.redrawOverlays();
  }

  redrawOverlays() {
    for (const axis of AXES) this.views[axis].drawOverlay();
  }
}
