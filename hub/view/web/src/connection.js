// The WebSocket to the view server (`/ws`): JSON text frames by "type", binary frames are the
// msgpack bodies message. Reconnects with a growing delay, so a restarted server is picked up
// without reloading the page, and a server that is gone is not hammered.

const FIRST_DELAY = 500;     // ms before the first reconnect
const MAX_DELAY = 8000;      // ms, the longest wait between attempts

export class Connection {
  /**
   * @param {string} url  ws://host/ws
   * @param {{onOpen?: Function, onClose?: Function, onMessage?: (msg: object) => void,
   *          onBinary?: (data: ArrayBuffer) => void}} handlers
   */
  constructor(url, handlers) {
    this.url = url;
    this.handlers = handlers;
    this.socket = null;
    this.delay = FIRST_DELAY;
    this.connected = false;
  }

  open() {
    const socket = new WebSocket(this.url);
    socket.binaryType = 'arraybuffer';
    socket.onopen = () => {
      this.connected = true;
      this.delay = FIRST_DELAY;
      this.handlers.onOpen?.();
    };
    socket.onmessage = (event) => this._receive(event.data);
    // onerror is always followed by onclose, which is where the retry lives.
    socket.onclose = () => {
      const was = this.connected;
      this.connected = false;
      this.socket = null;
      if (was) this.handlers.onClose?.();
      setTimeout(() => this.open(), this.delay);
      this.delay = Math.min(this.delay * 2, MAX_DELAY);
    };
    this.socket = socket;
  }

  _receive(data) {
    if (data instanceof ArrayBuffer) {
      this.handlers.onBinary?.(data);
      return;
    }
    let message;
    try {
      message = JSON.parse(data);
    } catch (err) {
      console.warn('planthub view: a text frame that is not JSON', err);
      return;
    }
    if (message && typeof message.type === 'string') this.handlers.onMessage?.(message);
  }

  /** Send one JSON message; false when the socket is not open (the caller says so to the user). */
  send(message) {
    if (!this.connected || !this.socket) return false;
    this.socket.send(JSON.stringify(message));
    return true;
  }
}

/** ws(s)://<this page's host>/ws */
export function socketUrl(location) {
  const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
  return `${scheme}//${location.host}/ws`;
}
