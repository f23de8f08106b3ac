// The plots of a recorded run (`planthub view RUN_DIR`): the slots recording.csv holds — what
// `planthub plot` draws — over the whole run, one chosen at a time (a vec3's components together),
// with a cursor at the playback time. From the server's one "recording" frame:
// {rate, start, end, slots: {slot: [column, …]}, series: {column: {ticks, values}}}.

import { Chart } from './chart.js';

const REDRAW_MS = 250;

export class RecordedPlots {
  constructor(box) {
    this.box = box;
    this.select = box.querySelector('#recorded-slot');
    this.chart = new Chart(box, 'Recorded slot over the run');
    this.recording = null;
    this.shown = '';
    this.select.addEventListener('change', () => this.choose(this.select.value));
    this._timer = setInterval(() => this.chart.draw(), REDRAW_MS);
  }

  /** The "recording" frame. */
  set(m) {
    this.recording = m;
    const names = Object.keys(m.slots ?? {});
    this.select.replaceChildren(...names.map((name) => {
      const o = document.createElement('option');
      o.value = o.textContent = name;
      return o;
    }));
    this.box.hidden = false;
    this.choose(names.includes(this.shown) ? this.shown : names[0] ?? '');
  }

  /** Draw one recorded slot (all its columns) over the run. */
  choose(name) {
    const m = this.recording;
    this.shown = name;
    this.select.value = name;
    this.chart.clear();
    if (!m || !name) return;
    const rate = m.rate || 150;
    this.chart.span = [m.start ?? 0, m.end ?? 0];
    const columns = m.slots[name] ?? [];
    for (const column of columns) {
      const s = m.series?.[column];
      if (!s) continue;
      const label = columns.length > 1 ? column.slice(name.length + 1) : column;
      this.chart.set(label, s.ticks.map((tick, i) => [tick / rate, s.values[i]]));
    }
  }

  /** The playback time, s: the cursor. */
  mark(t) {
    if (t !== null && t !== undefined) this.chart.mark(t);
  }
}
