// The playback bar of a recorded run (`planthub view RUN_DIR`, hello's "mode": "playback"): play,
// pause, speed and a time slider over the recording's span. It only asks; the server's clock
// decides, and its "playback" frames say what it did (hub/view/frames.py).

const SEEK_MS = 100;   // while the slider is dragged, at most one seek per this many ms (the last one always goes)

export class PlayBar {
  /** @param {(msg: object) => boolean} send  puts a message on the socket; false if closed */
  constructor(root, send) {
    this.root = root;
    this.send = send;
    this.$ = (sel) => root.querySelector(sel);
    this.start = 0;
    this.end = 0;
    this.playing = false;
    this.speed = 1;
    this.dragging = false;
    this.seeks = 0;          // seeks sent whose answer has not come: the slider waits for them
    this._queued = null;     // a seek held back while dragging
    this._timer = null;
    this.$('#play').addEventListener('click', () => this._ask('play'));
    this.$('#pause').addEventListener('click', () => this._ask('pause'));
    this.$('#speed').addEventListener('change', (e) => this._ask('speed', Number(e.target.value)));
    const scrub = this.$('#scrub');
    scrub.addEventListener('input', () => { this.dragging = true; this._seek(Number(scrub.value), false); });
    scrub.addEventListener('change', () => { this._seek(Number(scrub.value), true); this.dragging = false; });
  }

  /** A hello of a recorded run: its span and pace. */
  show(hello) {
    this.start = Number(hello.start ?? 0);
    this.end = Number(hello.end ?? 0);
    const scrub = this.$('#scrub');
    scrub.min = String(this.start);
    scrub.max = String(this.end);
    scrub.step = String(1 / (hello.rate || 150));
    scrub.value = String(this.start);
    this.root.hidden = false;
    this._time(this.start);
  }

  /** The server's {"type": "playback", op, time, tick, playing, speed, jump}. */
  state(m) {
    this.playing = !!m.playing;
    this.speed = Number(m.speed ?? 1);
    if (m.op === 'seek' && this.seeks > 0) this.seeks--;
    this.$('#play').disabled = this.playing;
    this.$('#pause').disabled = !this.playing;
    const speed = this.$('#speed');
    if (Number(speed.value) !== this.speed) speed.value = String(this.speed);
    this.root.dataset.playing = this.playing ? 'yes' : 'no';
  }

  /** An error frame about a seek: no answer will come for it. */
  refused(m) {
    if (m.op === 'seek' && this.seeks > 0) this.seeks--;
  }

  /** The plant time drawn now (s), each frame: the slider follows unless it is held. */
  update(t) {
    if (t === null || t === undefined) return;
    if (!this.dragging && this.seeks === 0) this.$('#scrub').value = String(t);
    this._time(t);
  }

  _time(t) {
    this.$('#playback-time').textContent = `${t.toFixed(2)} / ${this.end.toFixed(2)} s`;
  }

  _ask(op, value) {
    const message = { type: 'playback', op };
    if (value !== undefined) message.value = value;
    return this.send(message);
  }

  _seek(t, last) {
    this._queued = t;
    if (last) return this._flush();
    if (this._timer === null) {
      this._flush();
      this._timer = setTimeout(() => { this._timer = null; if (this._queued !== null) this._flush(); }, SEEK_MS);
    }
  }

  _flush() {
    const t = this._queued;
    this._queued = null;
    if (t === null) return;
    if (this._ask('seek', Math.min(this.end, Math.max(this.start, t)))) this.seeks++;
  }
}
