// The live plots: belt speeds from the "slots" messages (the view server watches every
// `*/drive/velocity`), bottles delivered and on the line and the throughput from the figures.

import { Chart } from './chart.js';

const REDRAW_MS = 250;   // plots change slowly; redrawing every frame would cost for nothing

/** "feed.drive.velocity" → "feed" (the usual belt drive), "lane.spur.velocity" → "lane.spur". */
function beltName(key) {
  const parts = key.split('.');
  if (parts.at(-1) === 'velocity') parts.pop();
  if (parts.length === 2 && parts[1] === 'drive') parts.pop();
  return parts.join('.');
}

export class Plots {
  constructor(box) {
    this.speeds = new Chart(box, 'Belt speeds', { window: 60, unit: '' });
    this.bottles = new Chart(box, 'Bottles: delivered, on the line', { window: 300 });
    this.pace = new Chart(box, 'Throughput, bottles per minute', { window: 300 });
    this.rate = 150;           // physics ticks per s, from the scene
    this.latest = new Map();   // belt object → speed m/s (the belts' stripes scroll at it)
    this._timer = setInterval(() => this.draw(), REDRAW_MS);
  }

  setScene(doc) {
    this.rate = doc.physics_rate || 150;
    this.latest.clear();
    for (const chart of [this.speeds, this.bottles, this.pace]) chart.clear();
  }

  /** A recorded run: its figures are the final ones, so the two charts drawn from them over time go. */
  recordedRun() {
    this.bottles.figure.hidden = this.pace.figure.hidden = true;
  }

  /** {"type": "slots", tick, values: {"obj.comp.slot": v}} */
  slots(message) {
    const t = (message.tick ?? 0) / this.rate;
    for (const [key, v] of Object.entries(message.values ?? {})) {
      if (!key.endsWith('.velocity')) continue;
      this.speeds.add(beltName(key), t, v);
      const object = key.split('.')[0];
      // An object with several belts has one stripe speed: its `drive`'s, else the first seen.
      if (key === `${object}.drive.velocity` || !this.latest.has(object)) this.latest.set(object, v);
    }
  }

  /** The figures map: plots what the plant section has. */
  figures(f) {
    const plant = f.sections?.plant;
    if (!plant) return;
    const t = f.time ?? 0;
    this.bottles.add('delivered', t, plant.delivered);
    this.bottles.add('on the line', t, plant.on_line?.length);
    if (plant.rejected) this.bottles.add('rejected', t, plant.rejected.length);
    this.pace.add('per minute', t, plant.throughput?.per_minute);
  }

  /** A belt object's speed, m/s, for the belt stripes (undefined: not watched). */
  speedOf(object) {
    return this.latest.get(object);
  }

  draw() {
    for (const chart of [this.speeds, this.bottles, this.pace]) chart.draw();
  }
}
