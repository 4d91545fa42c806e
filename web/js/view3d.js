// The 3-D view: draws the server's FRME JPEGs into a canvas and turns mouse,
// touch, wheel and keys into `nav` messages.
//
// Navigation follows the Navigator's contract (vv_nav_apply on the server):
// deltas in CSS pixels, `moving: true` while a gesture goes on (the server
// answers with cheap previews) and one last message with `moving: false`
// (the server then refines to the sharp frame).

import { clamp, debounce, fitRect } from './util.js';

// A wheel burst or a key repeat ends after this long without input.
const BURST_END_MS = 150;
// Zoom factor per 100 px of wheel deltaY (1.1 = 10 % closer per notch).
const WHEEL_BASE = 1.1;
// Deltas of one arrow-key press, in pixels.
const KEY_STEP = 12;
// What one nav message may carry (the server closes a client for more):
// VV_NAV_MAX_PIXELS, and a zoom factor in [1/16, 16]. More waits for the next.
const MAX_PIXELS = 4096;
const MAX_FACTOR = 16;

export class View3D {
  /**
   * canvas: the <canvas>; conn: the Connection; hooks: {onFrame(header),
   * onError(text)} called after a frame is drawn and when one cannot be decoded.
   */
  constructor(canvas, conn, hooks) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d', { alpha: false });
    this.conn = conn;
    this.hooks = hooks;

    this.cssSize = { width: 0, height: 0 }; // of the canvas, CSS pixels
    this.sentSize = null; // last size told to the server
    this.bitmap = null; // the frame on screen, kept to redraw on resize
    this.header = null;
    this.newest = null; // {header, blob}: the newest frame not yet decoded
    this.decoding = false;
    this.lastDraw = 0;

    this.seq = 0; // nav.seq: grows by one with every nav message
    this.pending = new Map(); // motion -> {dx, dy, factor} not yet sent
    this.raf = 0;
    this.burstTimers = new Map(); // motion -> timer ending a wheel/key burst
    this.drag = null; // mouse/pen drag: {id, motion, x, y}
    this.touches = new Map(); // pointerId -> {x, y}
    this.touchMotion = null; // the last motion of the current touch gesture

    this.bindPointer();
    this.bindWheelAndKeys();
    this.observeSize();
  }

  // ---- size ----

  observeSize() {
    const sendResize = debounce(() => this.sendSize('resize'), 200);
    new ResizeObserver((entries) => {
      const box = entries[entries.length - 1].contentRect;
      this.cssSize = { width: box.width, height: box.height };
      const dpr = window.devicePixelRatio || 1;
      // The backing store follows the screen's pixels so that the scaled-up
      // previews are smoothed once, by drawImage, not again by the compositor.
      this.canvas.width = Math.max(1, Math.round(box.width * dpr));
      this.canvas.height = Math.max(1, Math.round(box.height * dpr));
      this.draw();
      if (this.sentSize) sendResize();
    }).observe(this.canvas);
  }

  /** The view's size in CSS pixels as the protocol takes it (16..4096). */
  viewSize() {
    const rect = this.canvas.getBoundingClientRect();
    const w = this.cssSize.width || rect.width;
    const h = this.cssSize.height || rect.height;
    return { width: clamp(Math.round(w), 16, 4096), height: clamp(Math.round(h), 16, 4096) };
  }

  /** Sends `hello` (on open) or `resize` (when the size changed). */
  sendSize(type) {
    const size = this.viewSize();
    if (type === 'resize' && this.sentSize &&
        size.width === this.sentSize.width && size.height === this.sentSize.height) return;
    if (this.conn.send({ type, ...size })) this.sentSize = size;
  }

  // ---- frames ----

  /** An FRME message: decodes the newest frame; older ones are dropped. */
  onFrame(header, payload) {
    this.newest = { header, blob: new Blob([payload], { type: 'image/jpeg' }) };
    if (!this.decoding) this.decodeNewest();
  }

  async decodeNewest() {
    this.decoding = true;
    while (this.newest) {
      const f = this.newest;
      this.newest = null;
      let bitmap;
      try {
        bitmap = await createImageBitmap(f.blob);
      } catch (err) {
        this.hooks.onError(`frame ${f.header.seq} could not be decoded: ${err.message}`);
        continue;
      }
      // A newer frame came while this one decoded: show that one instead,
      // unless frames come faster than they decode and nothing would ever
      // be drawn (then this one is better than a frozen view).
      if (this.newest && performance.now() - this.lastDraw < 250) {
        bitmap.close();
        continue;
      }
      this.bitmap?.close();
      this.bitmap = bitmap;
      this.header = f.header;
      this.draw();
      this.lastDraw = performance.now();
      this.hooks.onFrame(f.header);
    }
    this.decoding = false;
  }

  draw() {
    const { ctx, canvas } = this;
    ctx.fillStyle = '#000';
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    const bm = this.bitmap;
    if (!bm) return;
    const r = fitRect(bm.width, bm.height, canvas.width, canvas.height, 0.03);
    ctx.imageSmoothingEnabled = true;
    ctx.imageSmoothingQuality = 'high';
    ctx.drawImage(bm, r.x, r.y, r.w, r.h);
  }

  // ---- navigation messages ----

  /** Adds a motion to what the next animation frame sends. */
  add(motion, dx, dy, factor = 1) {
    let p = this.pending.get(motion);
    if (!p) {
      p = { dx: 0, dy: 0, factor: 1 };
      this.pending.set(motion, p);
    }
    p.dx += dx;
    p.dy += dy;
    p.factor *= factor;
    // Pointer events come faster than frames: one nav message per motion
    // per animation frame, carrying the sum of the deltas.
    if (!this.raf) {
      this.raf = requestAnimationFrame(() => {
        this.raf = 0;
        for (const m of this.pending.keys()) this.sendPending(m, true, false);
      });
    }
  }

  /**
   * Sends what is pending for `motion`. With `force` a message goes even
   * with nothing pending (the last one of a gesture says moving: false).
   * dx, dy go as whole pixels; the fraction waits for the next message.
   */
  sendPending(motion, moving, force) {
    const p = this.pending.get(motion) ?? { dx: 0, dy: 0, factor: 1 };
    const msg = { type: 'nav', motion, seq: 0, moving };
    if (motion === 'zoom') {
      if (p.factor === 1 && !force) return;
      msg.factor = clamp(p.factor, 1 / MAX_FACTOR, MAX_FACTOR);
      p.factor /= msg.factor;
    } else {
      const dx = clamp(Math.round(p.dx), -MAX_PIXELS, MAX_PIXELS);
      const dy = clamp(Math.round(p.dy), -MAX_PIXELS, MAX_PIXELS);
      if (dx === 0 && dy === 0 && !force) return;
      msg.dx = dx;
      msg.dy = dy;
      p.dx -= dx;
      p.dy -= dy;
    }
    msg.seq = ++this.seq;
    this.conn.send(msg);
    if (!moving) this.pending.delete(motion);
  }

  /** The end of a gesture: what is pending goes out, the gesture's own motion last with moving: false. */
  endGesture(motion) {
    cancelAnimationFrame(this.raf);
    this.raf = 0;
    for (const m of [...this.pending.keys()]) if (m !== motion) this.sendPending(m, true, false);
    this.sendPending(motion, false, true);
  }

  /** A wheel notch or a key press: moving now, moving: false after a pause. */
  burst(motion, dx, dy, factor) {
    this.add(motion, dx, dy, factor);
    clearTimeout(this.burstTimers.get(motion));
    this.burstTimers.set(motion, setTimeout(() => {
      this.burstTimers.delete(motion);
      this.endGesture(motion);
    }, BURST_END_MS));
  }

  // ---- input ----

  bindPointer() {
    const c = this.canvas;
    c.addEventListener('contextmenu', (e) => e.preventDefault());
    c.addEventListener('pointerdown', (e) => this.pointerDown(e));
    c.addEventListener('pointermove', (e) => this.pointerMove(e));
    c.addEventListener('pointerup', (e) => this.pointerUp(e));
    c.addEventListener('pointercancel', (e) => this.pointerUp(e));
  }

  pointerDown(e) {
    if (e.pointerType === 'touch') {
      this.touches.set(e.pointerId, { x: e.clientX, y: e.clientY });
      this.canvas.setPointerCapture(e.pointerId);
      e.preventDefault();
      return;
    }
    if (this.drag) return;
    let motion = null;
    if (e.button === 0) motion = e.shiftKey ? 'pan' : 'rotate';
    else if (e.button === 1 || e.button === 2) motion = 'pan';
    if (!motion) return;
    this.drag = { id: e.pointerId, motion, x: e.clientX, y: e.clientY };
    this.canvas.setPointerCapture(e.pointerId);
    this.canvas.focus({ preventScroll: true });
    e.preventDefault();
  }

  pointerMove(e) {
    if (e.pointerType === 'touch') {
      this.touchMove(e);
      return;
    }
    const d = this.drag;
    if (!d || e.pointerId !== d.id) return;
    this.add(d.motion, e.clientX - d.x, e.clientY - d.y);
    d.x = e.clientX;
    d.y = e.clientY;
  }

  pointerUp(e) {
    if (e.pointerType === 'touch') {
      if (!this.touches.delete(e.pointerId)) return;
      if (this.touches.size === 0 && this.touchMotion) {
        this.endGesture(this.touchMotion);
        this.touchMotion = null;
      }
      return;
    }
    const d = this.drag;
    if (!d || e.pointerId !== d.id) return;
    this.drag = null;
    this.endGesture(d.motion);
  }

  /**
   * One finger rotates; two pinch (zoom by the ratio of their distances)
   * and pan (by the motion of their midpoint). Each pointer keeps its own
   * last position, so lifting one of two fingers does not make the view jump.
   */
  touchMove(e) {
    const t = this.touches.get(e.pointerId);
    if (!t) return;
    if (this.touches.size === 1) {
      this.add('rotate', e.clientX - t.x, e.clientY - t.y);
      this.touchMotion = 'rotate';
    } else {
      const [a, b] = [...this.touches.entries()].slice(0, 2);
      const other = (a[0] === e.pointerId ? b : a)?.[1];
      if (other && (a[0] === e.pointerId || b[0] === e.pointerId)) {
        const before = Math.hypot(t.x - other.x, t.y - other.y);
        const after = Math.hypot(e.clientX - other.x, e.clientY - other.y);
        if (before > 4 && after > 4) this.add('zoom', 0, 0, after / before);
        // the midpoint moves by half of one finger's motion
        this.add('pan', (e.clientX - t.x) / 2, (e.clientY - t.y) / 2);
        this.touchMotion = 'pan';
      }
    }
    t.x = e.clientX;
    t.y = e.clientY;
  }

  bindWheelAndKeys() {
    // not passive: the page itself must not scroll or zoom
    this.canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      let dy = e.deltaY;
      if (e.deltaMode === WheelEvent.DOM_DELTA_LINE) dy *= 40;
      else if (e.deltaMode === WheelEvent.DOM_DELTA_PAGE) dy *= 800;
      if (dy !== 0) this.burst('zoom', 0, 0, WHEEL_BASE ** (-dy / 100));
    }, { passive: false });

    this.canvas.addEventListener('keydown', (e) => {
      if (e.altKey || e.ctrlKey || e.metaKey) return;
      const motion = e.shiftKey ? 'pan' : 'rotate';
      const arrows = {
        ArrowLeft: [-KEY_STEP, 0], ArrowRight: [KEY_STEP, 0],
        ArrowUp: [0, -KEY_STEP], ArrowDown: [0, KEY_STEP],
      };
      if (arrows[e.key]) this.burst(motion, ...arrows[e.key], 1);
      else if (e.key === '+' || e.key === '=') this.burst('zoom', 0, 0, WHEEL_BASE);
      else if (e.key === '-' || e.key === '_') this.burst('zoom', 0, 0, 1 / WHEEL_BASE);
      else if (e.key === 'r' || e.key === 'R') this.conn.send({ type: 'reset_view' });
      else return;
      e.preventDefault();
    });
  }
}
