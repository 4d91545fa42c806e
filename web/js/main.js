// VolVis browser client: connects to `volvis serve` (docs/serve-protocol.md)
// and wires the 3-D view, the slice views and the panel to the socket.

import { Connection } from './wire.js';
import { View3D } from './view3d.js';
import { SliceViews } from './slices.js';
import { Panel } from './panel.js';
import { formatNumber } from './util.js';

// The server answered the page with the token in a cookie; the token stays
// out of the address bar, the history and bookmarks.
{
  const url = new URL(location.href);
  if (url.searchParams.has('token')) {
    url.searchParams.delete('token');
    history.replaceState(history.state, '', url.pathname + url.search + url.hash);
  }
}

const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
const conn = new Connection(`${scheme}//${location.host}/ws`);

// What tests (tests/web/) read; nothing of the page depends on it.
const api = {
  frames: 0, // FRME frames drawn
  lastFrame: null, // header of the last frame drawn
  state: null, // the last `state`
  lastPng: null, // Uint8Array of the last PNG_ payload
  lastProbe: null, // the last `probe` reply to the pointer
  errors: [], // messages of the `error`s received
  remote: null, // the last `remote` (reads of remote stores pending)
  remoteShown: [], // the texts the status line showed for them, in order
  connected: false,
  closed: null, // {code, reason} once the socket closed
  send: (msg) => conn.send(msg),
};
window.volvis = api;

// ---- status line ----

const statusConn = document.getElementById('status-conn');
const statusFrame = document.getElementById('status-frame');
const statusMsg = document.getElementById('status-msg');
const statusRemote = document.getElementById('status-remote');
const viewInfo = document.getElementById('view3d-info');

function showMessage(text, isError = false) {
  statusMsg.textContent = text;
  statusMsg.classList.toggle('error', isError);
  statusMsg.title = text;
}

function showError(text) {
  console.warn('volvis:', text);
  showMessage(text, true);
}

function showConnection(text, ok) {
  statusConn.textContent = text;
  statusConn.classList.toggle('ok', ok);
  statusConn.classList.toggle('bad', !ok);
}

function showFrame(h) {
  const ms = (v) => (Number.isFinite(v) ? `${formatNumber(v)} ms` : '–');
  statusFrame.textContent =
    `${h.kind ?? 'frame'}${h.sharp ? ' (sharp)' : ''} · ${h.width}×${h.height} · ` +
    `render ${ms(h.render_ms)} · encode ${ms(h.encode_ms)}`;
  viewInfo.textContent = h.sharp ? '' : 'preview';
}

// Reads of remote stores (HTTP, S3) not yet answered: "12 chunks, 3.4 MB
// pending" (kB under a megabyte) while a frame waits for the network,
// hidden when none are.
function showRemote(m) {
  const n = m.pending;
  let text = '';
  if (n > 0) {
    text = `${n} ${n === 1 ? 'chunk' : 'chunks'}`;
    const b = m.pending_bytes;
    if (b >= 1e6) text += `, ${(b / 1e6).toFixed(1)} MB`;
    else if (b > 0) text += `, ${Math.ceil(b / 1e3)} kB`;
    text += ' pending';
  }
  statusRemote.textContent = text;
  statusRemote.hidden = n === 0;
  api.remoteShown.push(text);
}

// ---- the parts ----

const view = new View3D(document.getElementById('view3d'), conn, {
  onFrame(header) {
    api.frames++;
    api.lastFrame = header;
    showFrame(header);
  },
  onError: showError,
});

const slices = new SliceViews(conn, {
  onError: showError,
  onProbe: (msg) => {
    api.lastProbe = msg;
  },
});
// the `seq` of the last nav message sent: a frame whose input_seq reaches it shows all input
Object.defineProperty(api, 'navSeq', { get: () => view.seq, enumerable: true });

const panel = new Panel(conn, {
  onInfo: (text) => showMessage(text),
  onPng: (bytes) => {
    api.lastPng = bytes;
  },
});

// ---- messages ----

conn.on('open', () => {
  api.connected = true;
  showConnection('connected', true);
  view.sendSize('hello'); // the first message, as the protocol asks
  panel.list('');
  slices.onOpen();
});

conn.on('close', ({ code, reason }) => {
  api.connected = false;
  api.closed = { code, reason };
  showConnection(`disconnected (${code}${reason ? `: ${reason}` : ''}); reload the page to reconnect`, false);
});

conn.on('client-error', showError);

conn.on('remote', (m) => {
  api.remote = m;
  showRemote(m);
});

conn.on('state', (s) => {
  api.state = s;
  if (!s.dims && api.frames === 0) viewInfo.textContent = 'Nothing is open: choose a file under Files.';
  panel.onState(s);
  slices.onState(s);
});

conn.on('error', (msg) => {
  const text = typeof msg.message === 'string' ? msg.message : 'error';
  api.errors.push(text);
  showError(text);
  panel.opening = null;
});

conn.on('probe', (msg) => slices.onProbe(msg));

conn.on('listing', (msg) => panel.onListing(msg));
conn.on('saved', (msg) => panel.onSaved(msg));
conn.on('FRME', (header, payload) => view.onFrame(header, payload));
conn.on('SLCE', (header, payload) => slices.onSlice(header, payload));
conn.on('THMB', (header, payload) => panel.onThumb(header, payload));
conn.on('PNG_', (header, payload) => panel.onPng(header, payload));

conn.connect();
