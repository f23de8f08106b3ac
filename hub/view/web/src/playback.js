// The playback clock: samples come at ~20 Hz of plant time with network and event-loop jitter
// (a busy page takes several frames' worth of messages at once), frames at the display's rate.
// Drawing the newest sample would move bottles in jumps; instead the view plays plant time back
// a little behind the newest sample and interpolates between the two samples around it.
//
// The clock is a line through the arrivals: plant time = rate·wall + offset. `rate` (the run's
// pace: 1 for a real-time run, more for one faster than real time) is fitted to the recent
// arrivals; `offset` is set by the *latest* of them relative to that line, less one sample
// interval, so the newest sample is almost always ahead of the clock and the clock never has to
// wait — it stays smooth even when messages come in bunches.
//
// A recorded run's playback (`planthub view RUN_DIR`) knows its pace — the speed the trainer
// chose — so it is set, not fitted (setPace), and a seek is a jump: what was kept belongs to
// another time, so it is dropped and nothing is interpolated across it (jump).

const KEEP = 16;             // samples kept for interpolation: enough to bridge a late frame or two
const FIT = 60;              // arrivals the pace is fitted to (3 s at 20 Hz)
const LATE = 20;             // arrivals whose lateness sets the lag
const PULL_SECONDS = 1.0;    // wall time over which a clock error is mostly corrected
const SNAP = 2.0;            // plant s: further off than this (a new run, a jump) → jump the clock
const GAP = 1.0;             // wall s: a longer silence (paused, stepping) starts the fit anew

export class Playback {
  constructor() {
    this.rate = 1.0;         // plant seconds per wall second; kept across clears
    this.fixed = false;      // the rate is set (a recorded run's speed), not fitted
    this.clear();
  }

  /** A known pace (plant s per wall s), as a recorded run's playback has it; null: fit it again. */
  setPace(rate) {
    const changed = rate !== null && rate !== this.rate;
    this.fixed = rate !== null;
    if (this.fixed) this.rate = rate;
    if (changed) this.arrivals.length = 0;   // the line through the arrivals has another slope now
  }

  /** The plant time jumped (a seek): drop the samples, so the next one is shown as it is. */
  jump() {
    this.clear();
  }

  clear() {
    this.samples = [];       // ascending in time
    this.arrivals = [];      // [wall s, plant s] of recent samples, for the fit
    this.clock = null;       // plant time being shown
    this.interval = 0.05;    // plant seconds between samples, estimated
  }

  get newest() {
    return this.samples.length ? this.samples[this.samples.length - 1] : null;
  }

  /** Take a decoded sample; `now` is wall time in s. */
  push(sample, now) {
    const newest = this.newest;
    if (newest && sample.time < newest.time) {
      // Time went back: a new run or a restarted hub. What we had belongs to another timeline.
      this.clear();
    } else if (newest && sample.time === newest.time) {
      this.samples[this.samples.length - 1] = sample;
      return;
    }
    if (newest) this.interval += 0.2 * (sample.time - newest.time - this.interval);
    const last = this.arrivals.at(-1);
    if (last && now - last[0] > GAP) this.arrivals.length = 0;
    this.arrivals.push([now, sample.time]);
    if (this.arrivals.length > FIT) this.arrivals.shift();
    this._fitRate();
    this.samples.push(sample);
    if (this.samples.length > KEEP) this.samples.shift();
  }

  /** Least squares slope of plant time over wall time, once the arrivals span a while. */
  _fitRate() {
    if (this.fixed) return;
    const a = this.arrivals, n = a.length;
    if (n < 4 || a[n - 1][0] - a[0][0] < 0.3) return;
    let sw = 0, sp = 0;
    for (const [w, p] of a) { sw += w; sp += p; }
    const mw = sw / n, mp = sp / n;
    let num = 0, den = 0;
    for (const [w, p] of a) { num += (w - mw) * (p - mp); den += (w - mw) ** 2; }
    if (den > 0 && num > 0) this.rate = num / den;
  }

  /** Where the clock should be at wall time `now`: behind the latest of the recent arrivals. */
  _target(now) {
    let offset = Infinity;
    const a = this.arrivals;
    for (let i = Math.max(0, a.length - LATE); i < a.length; i++) offset = Math.min(offset, a[i][1] - this.rate * a[i][0]);
    return this.rate * now + offset - this.interval;
  }

  /** Advance the clock to wall time `now` (s), `dt` s after the last frame; returns the plant time to show (null: nothing yet). */
  advance(now, dt) {
    const newest = this.newest;
    if (!newest) return null;
    const target = this.arrivals.length ? this._target(now) : newest.time;
    if (this.clock === null || Math.abs(target - this.clock) > SNAP) {
      this.clock = target;
    } else {
      this.clock += dt * this.rate;
      this.clock += (target - this.clock) * Math.min(1, dt / PULL_SECONDS);
    }
    // Never run ahead of what we know (no extrapolation) nor behind what we kept.
    this.clock = Math.min(Math.max(this.clock, this.samples[0].time), newest.time);
    return this.clock;
  }

  /**
   * The two samples around plant time `t` and the fraction between them: {a, b, f} with
   * a.time <= t <= b.time (a === b when t is at an end of the buffer).
   */
  bracket(t) {
    const s = this.samples;
    for (let i = s.length - 1; i > 0; i--) {
      if (s[i - 1].time <= t) {
        const a = s[i - 1], b = s[i];
        const span = b.time - a.time;
        return { a, b, f: span > 0 ? Math.min(1, Math.max(0, (t - a.time) / span)) : 1 };
      }
    }
    return { a: s[0], b: s[0], f: 0 };
  }
}
