// The side panel: render mode, transfer-function presets, channels, time,
// the file browser, Save session and the PNG download.

import { el, formatBytes, formatNumber, idPart } from './util.js';

const THUMB_SIZE = 96;

export class Panel {
  /** hooks: {onInfo(text), onPng(bytes)} */
  constructor(conn, hooks) {
    this.conn = conn;
    this.hooks = hooks;
    this.state = null;
    this.presetsKey = null;
    this.thumbsKey = null;
    this.thumbUrls = new Map(); // preset name -> blob URL of its thumbnail
    this.channelsKey = null;
    this.filesPath = '';
    this.opening = null; // the file asked for, until a state shows it
    this.pngUrl = null;
    this.pngWanted = false;
    this.$ = (id) => document.getElementById(id);
    this.bindView();
    this.bindTime();
    this.bindSession();
    this.bindRemote();
  }

  // ---- state ----

  onState(s) {
    if (this.opening && s.name && s.name !== this.state?.name) {
      this.hooks.onInfo(`opened ${this.opening}`);
      this.opening = null;
    }
    this.state = s;
    this.showDataset(s);
    this.showMode(s);
    this.showPresets(s);
    this.showChannels(s);
    this.showTime(s);
    this.showFilesPath();
  }

  showDataset(s) {
    const parts = [s.name || '(nothing open)'];
    if (Array.isArray(s.dims)) parts.push(s.dims.join(' × '));
    if (Array.isArray(s.spacing)) {
      parts.push(`${s.spacing.map(formatNumber).join(' × ')}${s.unit ? ` ${s.unit}` : ''}`);
    }
    if (s.renderer) parts.push(s.renderer);
    if (s.shared) parts.push('shared session');
    this.$('dataset').textContent = parts.join(' · ');
    document.title = s.name ? `${s.name} — VolVis` : 'VolVis';
  }

  // ---- mode ----

  bindView() {
    const mode = this.$('mode');
    const iso = this.$('isovalue');
    // The mode alone when it is chosen; the isovalue only once the user gives
    // one (the field shows the server's, rounded: sending it back would move it).
    mode.addEventListener('change', () => {
      this.$('isovalue-row').hidden = mode.value !== 'iso';
      this.conn.send({ type: 'mode', mode: mode.value });
    });
    iso.addEventListener('change', () => {
      const v = Number(iso.value);
      if (iso.value === '' || !Number.isFinite(v)) return;
      this.conn.send({ type: 'mode', mode: 'iso', isovalue: v });
    });
    this.$('reset-view').addEventListener('click', () => this.conn.send({ type: 'reset_view' }));
    this.$('png').addEventListener('click', () => {
      if (this.conn.send({ type: 'png' })) {
        this.pngWanted = true;
        this.hooks.onInfo('rendering the PNG…');
      }
    });
  }

  showMode(s) {
    const mode = this.$('mode');
    const iso = this.$('isovalue');
    if (document.activeElement !== mode && s.mode) {
      // a scene may use a mode the menu does not offer (minip, xray): show it
      if (![...mode.options].some((o) => o.value === s.mode)) {
        mode.append(el('option', { value: s.mode, textContent: s.mode, disabled: true }));
      }
      mode.value = s.mode;
    }
    if (document.activeElement !== iso && Number.isFinite(s.isovalue)) iso.value = formatNumber(s.isovalue);
    if (Array.isArray(s.range)) {
      iso.min = String(s.range[0]);
      iso.max = String(s.range[1]);
    }
    this.$('isovalue-row').hidden = mode.value !== 'iso';
  }

  // ---- presets ----

  showPresets(s) {
    const names = Array.isArray(s.presets) ? s.presets : [];
    const key = JSON.stringify(names);
    const box = this.$('presets');
    if (key !== this.presetsKey) {
      this.presetsKey = key;
      box.replaceChildren(...names.map((name) => {
        const b = el('button', {
          type: 'button', className: 'preset', id: `preset-${idPart(name)}`, title: name,
          attrs: { 'aria-label': name, 'aria-pressed': 'false', 'data-name': name },
        }, el('div', { className: 'thumb-empty' }), el('span', { textContent: name }));
        b.addEventListener('click', () => this.conn.send({ type: 'preset', name }));
        const url = this.thumbUrls.get(name);
        if (url) this.setThumb(b, url);
        return b;
      }));
    }
    for (const b of box.children) b.setAttribute('aria-pressed', String(b.dataset.name === s.preset));
    // Thumbnails show the data set: new ones when another one is opened.
    const thumbsKey = JSON.stringify([key, s.name, s.time]);
    if (names.length && thumbsKey !== this.thumbsKey) {
      this.thumbsKey = thumbsKey;
      this.conn.send({ type: 'thumbnails', size: THUMB_SIZE });
    }
  }

  onThumb(header, payload) {
    const name = header.name;
    const url = URL.createObjectURL(new Blob([payload], { type: 'image/jpeg' }));
    const old = this.thumbUrls.get(name);
    if (old) URL.revokeObjectURL(old);
    this.thumbUrls.set(name, url);
    const b = document.getElementById(`preset-${idPart(name)}`);
    if (b) this.setThumb(b, url);
  }

  setThumb(button, url) {
    const img = el('img', { src: url, alt: '', width: THUMB_SIZE, height: THUMB_SIZE });
    button.firstElementChild.replaceWith(img);
  }

  // ---- channels ----

  showChannels(s) {
    const channels = Array.isArray(s.channels) ? s.channels : [];
    const group = this.$('channels-group');
    group.hidden = channels.length <= 1;
    if (channels.length <= 1) return;
    const box = this.$('channels');
    const key = JSON.stringify(channels.map((c) => c.name));
    if (key !== this.channelsKey) {
      this.channelsKey = key;
      box.replaceChildren(...channels.map((c, index) => {
        const name = c.name || `channel ${index}`;
        const vis = el('input', { type: 'checkbox', id: `channel-${index}-visible` });
        const color = el('input', {
          type: 'color', id: `channel-${index}-color`, attrs: { 'aria-label': `${name} colour` },
        });
        vis.addEventListener('change', () => this.conn.send({ type: 'channel', index, visible: vis.checked }));
        color.addEventListener('change', () => this.conn.send({ type: 'channel', index, color: color.value }));
        return el('div', { className: 'channel' }, vis,
          el('label', { htmlFor: vis.id, textContent: name, title: name }), color);
      }));
    }
    channels.forEach((c, index) => {
      const vis = document.getElementById(`channel-${index}-visible`);
      const color = document.getElementById(`channel-${index}-color`);
      vis.checked = c.visible !== false;
      if (typeof c.color === 'string' && /^#[0-9a-fA-F]{6}$/.test(c.color) &&
          document.activeElement !== color) color.value = c.color.toLowerCase();
    });
  }

  // ---- time ----

  bindTime() {
    const t = this.$('time');
    let raf = 0;
    // a slider drag sends at most one step per animation frame
    t.addEventListener('input', () => {
      this.$('time-value').value = this.timeLabel(Number(t.value));
      if (raf) return;
      raf = requestAnimationFrame(() => {
        raf = 0;
        this.conn.send({ type: 'time', step: Number(t.value) });
      });
    });
  }

  timeLabel(step) {
    return `${step + 1}/${this.state?.time_steps ?? 1}`;
  }

  showTime(s) {
    const n = Number.isInteger(s.time_steps) ? s.time_steps : 1;
    this.$('time-group').hidden = n <= 1;
    if (n <= 1) return;
    const t = this.$('time');
    t.max = String(n - 1);
    if (document.activeElement !== t && Number.isInteger(s.time)) t.value = String(s.time);
    this.$('time-value').value = this.timeLabel(Number(t.value));
  }

  // ---- files ----

  list(path) {
    this.conn.send({ type: 'list', path });
  }

  onListing(msg) {
    const path = typeof msg.path === 'string' ? msg.path : '';
    this.filesPath = path;
    this.showFilesPath();
    const join = (name) => (path ? `${path}/${name}` : name);
    const items = [];
    if (path) {
      const up = path.split('/').slice(0, -1).join('/');
      items.push(this.fileItem('..', true, null, () => this.list(up), 'Parent folder'));
    }
    for (const e of Array.isArray(msg.entries) ? msg.entries : []) {
      // a folder that is one dataset (an OME-Zarr store) opens like a file
      if (e.dir && !e.store) {
        items.push(this.fileItem(`${e.name}/`, true, null, () => this.list(join(e.name)), `Folder ${e.name}`));
      } else {
        items.push(this.fileItem(e.name, false, e.store ? null : e.size, () => {
          if (this.conn.send({ type: 'open', path: join(e.name) })) {
            this.opening = join(e.name);
            this.hooks.onInfo(`opening ${this.opening}…`);
          }
        }, `Open ${e.name}`, e.store ? 'store' : 'file'));
      }
    }
    if (items.length === 0) items.push(el('li', { className: 'empty', textContent: '(empty)' }));
    this.$('files').replaceChildren(...items);
    // the top of the root also lists the remote data the server may open
    if (Array.isArray(msg.remote)) this.showRemote(msg.remote);
  }

  // ---- remote data (URLs given to `volvis serve`, and --allow-url prefixes) ----

  bindRemote() {
    const input = this.$('open-url');
    this.$('open-url-button').addEventListener('click', () => this.openUrl(input.value.trim()));
    input.addEventListener('keydown', (e) => {
      if (e.key === 'Enter') this.openUrl(input.value.trim());
    });
  }

  openUrl(url) {
    if (!url) {
      this.hooks.onInfo('Open URL: give a URL listed under Remote data, or one under a prefix');
      return;
    }
    if (this.conn.send({ type: 'open', url })) {
      this.opening = url;
      this.hooks.onInfo(`opening ${url}…`);
    }
  }

  /** A given URL opens on click; a prefix fills the URL field for the rest to be typed. */
  showRemote(remote) {
    const items = [];
    for (const r of remote) {
      if (typeof r.url !== 'string') continue;
      if (r.prefix) {
        items.push(this.fileItem(`${r.url}…`, false, null, () => {
          const input = this.$('open-url');
          input.value = r.url;
          input.focus();
          input.setSelectionRange(r.url.length, r.url.length);
        }, `Type a URL under ${r.url}`, 'prefix'));
      } else {
        items.push(this.fileItem(r.url, false, null, () => this.openUrl(r.url), `Open ${r.url}`,
          'url'));
      }
    }
    this.$('remote').replaceChildren(...items);
    this.$('remote-group').hidden = items.length === 0;
  }

  showFilesPath() {
    const root = this.state?.root || 'root';
    this.$('files-path').textContent = `${root}/${this.filesPath ? `${this.filesPath}/` : ''}`;
  }

  fileItem(name, dir, size, onClick, label, kind = dir ? 'dir' : 'file') {
    const b = el('button', { type: 'button', attrs: { 'aria-label': label, 'data-name': name } },
      el('span', { className: 'name', textContent: name }),
      el('span', { className: 'size', textContent: size == null ? '' : formatBytes(size) }));
    b.addEventListener('click', onClick);
    if (kind === 'store') b.append(el('span', { className: 'size', textContent: 'dataset' }));
    return el('li', { className: kind }, b);
  }

  // ---- session and PNG ----

  bindSession() {
    const input = this.$('save-path');
    const save = () => {
      const path = input.value.trim();
      if (!path) {
        this.hooks.onInfo('Save session: give a path ending in .json');
        return;
      }
      if (this.conn.send({ type: 'save', path })) this.hooks.onInfo(`saving ${path}…`);
    };
    this.$('save').addEventListener('click', save);
    input.addEventListener('keydown', (e) => {
      if (e.key === 'Enter') save();
    });
  }

  onSaved(msg) {
    this.hooks.onInfo(`session saved to ${msg.path}`);
  }

  onPng(header, payload) {
    const bytes = payload.slice(); // a copy: the message's buffer is not ours to keep
    this.hooks.onPng(bytes);
    if (this.pngUrl) URL.revokeObjectURL(this.pngUrl);
    this.pngUrl = URL.createObjectURL(new Blob([bytes], { type: 'image/png' }));
    const a = this.$('png-link');
    const name = `${(this.state?.name || 'volvis').replace(/\.[^.]*$/, '').replace(/[^\w.-]+/g, '_')}.png`;
    a.href = this.pngUrl;
    a.download = name;
    a.textContent = `${name} (${header.width}×${header.height})`;
    a.hidden = false;
    this.hooks.onInfo(`PNG ${header.width}×${header.height}, ${formatBytes(bytes.length)}`);
    if (this.pngWanted) {
      this.pngWanted = false;
      a.click(); // the download the user asked for
    }
  }
}
