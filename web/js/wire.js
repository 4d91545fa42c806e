// The WebSocket of docs/serve-protocol.md: text messages are one JSON object
// each; binary messages are 4 ASCII bytes of kind, a little-endian uint32 n,
// n bytes of JSON header, then the payload.

const decoder = new TextDecoder();

/**
 * Splits a binary message into {kind, header, payload}; payload is a view
 * into the message's buffer. Throws on a message too short for what it says.
 */
export function parseBinary(buffer) {
  if (buffer.byteLength < 8) {
    throw new Error(`binary message of ${buffer.byteLength} bytes is shorter than its 8-byte prefix`);
  }
  const bytes = new Uint8Array(buffer);
  const kind = String.fromCharCode(bytes[0], bytes[1], bytes[2], bytes[3]);
  const n = new DataView(buffer).getUint32(4, true);
  if (n > buffer.byteLength - 8) {
    throw new Error(`${kind}: a header of ${n} bytes overruns the ${buffer.byteLength}-byte message`);
  }
  const header = JSON.parse(decoder.decode(bytes.subarray(8, 8 + n)));
  return { kind, header, payload: bytes.subarray(8 + n) };
}

/**
 * One WebSocket to the server. Handlers are registered per message type
 * (`state`, `probe`, ...: called with the message) or binary kind (`FRME`,
 * `SLCE`, ...: called with header and payload), plus the events `open`,
 * `close` ({code, reason}) and `client-error` (a message we could not read).
 */
export class Connection {
  constructor(url) {
    this.url = url;
    this.ws = null;
    this.handlers = new Map();
  }

  on(type, fn) {
    if (!this.handlers.has(type)) this.handlers.set(type, []);
    this.handlers.get(type).push(fn);
    return this;
  }

  emit(type, ...args) {
    for (const fn of this.handlers.get(type) ?? []) {
      try {
        fn(...args);
      } catch (err) {
        // One broken handler must not stop the others or the socket.
        console.error(`volvis: handler of ${type}:`, err);
        if (type !== 'client-error') this.emit('client-error', `${type}: ${err.message}`);
      }
    }
  }

  get open() {
    return this.ws !== null && this.ws.readyState === WebSocket.OPEN;
  }

  connect() {
    const ws = new WebSocket(this.url, 'volvis');
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    ws.addEventListener('open', () => this.emit('open'));
    ws.addEventListener('close', (ev) => this.emit('close', { code: ev.code, reason: ev.reason }));
    ws.addEventListener('message', (ev) => this.receive(ev.data));
  }

  receive(data) {
    if (typeof data === 'string') {
      let msg;
      try {
        msg = JSON.parse(data);
      } catch (err) {
        this.emit('client-error', `unreadable message from the server: ${err.message}`);
        return;
      }
      if (msg === null || typeof msg !== 'object' || typeof msg.type !== 'string') {
        this.emit('client-error', 'a message from the server without a type');
        return;
      }
      if (!this.handlers.has(msg.type)) console.warn('volvis: unhandled message', msg.type);
      this.emit(msg.type, msg);
      return;
    }
    let m;
    try {
      m = parseBinary(data);
    } catch (err) {
      this.emit('client-error', err.message);
      return;
    }
    if (!this.handlers.has(m.kind)) console.warn('volvis: unhandled binary message', m.kind);
    this.emit(m.kind, m.header, m.payload);
  }

  /** Sends one message (an object, sent as JSON); false when the socket is not open. */
  send(msg) {
    if (!this.open) return false;
    this.ws.send(JSON.stringify(msg));
    return true;
  }
}
