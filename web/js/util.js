// Small helpers shared by the modules.

export const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));

/** fn, called once `ms` after the last of a burst of calls. */
export function debounce(fn, ms) {
  let timer = 0;
  return (...args) => {
    clearTimeout(timer);
    timer = setTimeout(() => fn(...args), ms);
  };
}

/**
 * A number for people: integers as they are, others with about four
 * significant digits (a trilinear sample of an integer volume is rarely whole).
 */
export function formatNumber(v) {
  if (typeof v !== 'number' || !Number.isFinite(v)) return String(v);
  if (Number.isInteger(v)) return String(v);
  const a = Math.abs(v);
  if (a >= 1000) return v.toFixed(0);
  if (a >= 100) return v.toFixed(1);
  if (a >= 1) return v.toFixed(2);
  return v.toPrecision(3);
}

export function formatBytes(n) {
  if (!Number.isFinite(n)) return '';
  if (n < 1024) return `${n} B`;
  const units = ['KiB', 'MiB', 'GiB', 'TiB'];
  let v = n;
  let u = -1;
  do {
    v /= 1024;
    u++;
  } while (v >= 1024 && u < units.length - 1);
  return `${v.toFixed(v < 10 ? 1 : 0)} ${units[u]}`;
}

/** document.createElement with properties, attributes (`attrs`) and children. */
export function el(tag, props = {}, ...children) {
  const e = document.createElement(tag);
  const { attrs, ...rest } = props;
  Object.assign(e, rest);
  for (const [k, v] of Object.entries(attrs ?? {})) e.setAttribute(k, v);
  for (const c of children) e.append(c);
  return e;
}

/** An id made of the characters ids and CSS selectors take without escaping. */
export const idPart = (s) => String(s).replace(/[^A-Za-z0-9_-]/g, '-');

/**
 * The rectangle (in the canvas's backing pixels) where an image of
 * `iw` x `ih` is drawn into a canvas of `cw` x `ch`: fitted whole and centred.
 * Images within `tolerance` (a fraction) of the canvas's aspect fill it
 * exactly, so that a preview frame whose size was rounded to whole pixels
 * does not leave a thin bar.
 */
export function fitRect(iw, ih, cw, ch, tolerance = 0) {
  if (iw <= 0 || ih <= 0 || cw <= 0 || ch <= 0) return { x: 0, y: 0, w: cw, h: ch };
  const ia = iw / ih;
  const ca = cw / ch;
  if (Math.abs(ia / ca - 1) <= tolerance) return { x: 0, y: 0, w: cw, h: ch };
  if (ia > ca) {
    const h = cw / ia;
    return { x: 0, y: (ch - h) / 2, w: cw, h };
  }
  const w = ch * ia;
  return { x: (cw - w) / 2, y: 0, w, h: ch };
}
