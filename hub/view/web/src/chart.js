// A small time-series chart on a canvas: a few named series over the last `window` seconds of
// plant time, y scaled to what is visible, a legend. Enough for a handful of live figures
// without a charting library. With a `span` it draws that whole stretch instead (a recorded run's
// series, set at once), and a `cursor` marks a time on it.

const PALETTE = ['#4e79a7', '#f28e2b', '#e15759', '#76b7b2', '#59a14f', '#edc948', '#b07aa1',
  '#ff9da7', '#9c755f', '#bab0ac', '#1f77b4', '#2ca02c', '#d62728', '#9467bd', '#8c564b',
  '#e377c2', '#7f7f7f', '#bcbd22', '#17becf'];
const MAX_POINTS = 2000;      // per series; older points are dropped
const PAD = { left: 40, right: 8, top: 8, bottom: 18 };

export class Chart {
  constructor(parent, title, { window = 60, unit = '' } = {}) {
    this.window = window;
    this.unit = unit;
    this.series = new Map();   // name → {colour, points: [[t, v]]}
    this.span = null;          // [t0, t1]: draw this stretch, not the last `window` s
    this.cursor = null;        // a time to mark, s
    this.dirty = true;
    const figure = this.figure = document.createElement('figure');
    figure.className = 'chart';
    const caption = document.createElement('figcaption');
    caption.textContent = title;
    this.canvas = document.createElement('canvas');
    this.legend = document.createElement('div');
    this.legend.className = 'chart-legend';
    figure.append(caption, this.canvas, this.legend);
    parent.append(figure);
  }

  clear() {
    this.series.clear();
    this.legend.replaceChildren();
    this.dirty = true;
  }

  add(name, t, v) {
    if (typeof v !== 'number' || !Number.isFinite(v)) return;
    let s = this.series.get(name);
    if (!s) {
      s = { colour: PALETTE[this.series.size % PALETTE.length], points: [] };
      this.series.set(name, s);
      this._legendEntry(name, s.colour);
    }
    const last = s.points.at(-1);
    if (last && t < last[0]) s.points.length = 0;   // time went back: a new run
    s.points.push([t, v]);
    if (s.points.length > MAX_POINTS) s.points.splice(0, s.points.length - MAX_POINTS);
    this.dirty = true;
  }

  /** A whole series at once: [[t, v], …] in time order (kept as given, however many). */
  set(name, points) {
    let s = this.series.get(name);
    if (!s) {
      s = { colour: PALETTE[this.series.size % PALETTE.length], points: [] };
      this.series.set(name, s);
      this._legendEntry(name, s.colour);
    }
    s.points = points.filter(([, v]) => typeof v === 'number' && Number.isFinite(v));
    this.dirty = true;
  }

  /** Mark time t (s); redrawn with the next draw. */
  mark(t) {
    if (t === this.cursor) return;
    this.cursor = t;
    this.dirty = true;
  }

  _legendEntry(name, colour) {
    const item = document.createElement('span');
    const swatch = document.createElement('i');
    swatch.style.background = colour;
    item.append(swatch, name);
    this.legend.append(item);
  }

  /** Redraw if anything changed (called a few times a second, not per frame). */
  draw() {
    if (!this.dirty) return;
    this.dirty = false;
    const c = this.canvas, ratio = window.devicePixelRatio || 1;
    const width = c.clientWidth || 300, height = c.clientHeight || 120;
    if (c.width !== Math.round(width * ratio) || c.height !== Math.round(height * ratio)) {
      c.width = Math.round(width * ratio);
      c.height = Math.round(height * ratio);
    }
    const g = c.getContext('2d');
    g.setTransform(ratio, 0, 0, ratio, 0, 0);
    g.clearRect(0, 0, width, height);
    let t1 = -Infinity, first = Infinity;
    for (const s of this.series.values()) {
      if (!s.points.length) continue;
      t1 = Math.max(t1, s.points.at(-1)[0]);
      first = Math.min(first, s.points[0][0]);
    }
    if (t1 === -Infinity) return;
    // Until a window's worth has come, the plot spans what there is, so it fills the width.
    let t0 = Math.max(t1 - this.window, Math.min(first, t1 - 1));
    if (this.span) [t0, t1] = [this.span[0], Math.max(this.span[1], this.span[0] + 1e-6)];
    const span = t1 - t0;
    let lo = 0, hi = -Infinity;
    for (const s of this.series.values()) {
      for (const [t, v] of s.points) {
        if (t < t0 || t > t1) continue;
        lo = Math.min(lo, v);
        hi = Math.max(hi, v);
      }
    }
    if (hi - lo < 1e-9) hi = lo + 1;
    hi += (hi - lo) * 0.08;
    const x = (t) => PAD.left + ((t - t0) / span) * (width - PAD.left - PAD.right);
    const y = (v) => height - PAD.bottom - ((v - lo) / (hi - lo)) * (height - PAD.top - PAD.bottom);
    this._axes(g, width, height, lo, hi, t0, t1, y);
    for (const s of this.series.values()) {
      g.strokeStyle = s.colour;
      g.lineWidth = 1.5;
      g.beginPath();
      let started = false;
      for (const [t, v] of s.points) {
        if (t < t0) continue;
        if (started) g.lineTo(x(t), y(v));
        else { g.moveTo(x(t), y(v)); started = true; }
      }
      g.stroke();
    }
    if (this.cursor !== null && this.cursor >= t0 && this.cursor <= t1) {
      g.strokeStyle = '#1f2328';
      g.lineWidth = 1;
      g.beginPath();
      g.moveTo(x(this.cursor), PAD.top);
      g.lineTo(x(this.cursor), height - PAD.bottom);
      g.stroke();
    }
  }

  _axes(g, width, height, lo, hi, t0, t1, y) {
    g.strokeStyle = '#d5d9de';
    g.fillStyle = '#69717b';
    g.font = '10px system-ui, sans-serif';
    g.lineWidth = 1;
    for (const v of [lo, (lo + hi) / 2, hi]) {
      g.beginPath();
      g.moveTo(PAD.left, y(v));
      g.lineTo(width - PAD.right, y(v));
      g.stroke();
      g.fillText(`${v.toPrecision(3)}${this.unit}`, 2, y(v) + 3);
    }
    g.fillText(`${t0.toFixed(0)} s`, PAD.left, height - 4);
    const end = `${t1.toFixed(0)} s`;
    g.fillText(end, width - PAD.right - g.measureText(end).width, height - 4);
  }
}
