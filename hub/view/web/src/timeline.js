// The checkpoint timeline of the operator panel: the checkpoints a rewind may go back to (the
// hub's `checkpoints` message, schemas/wire.md), as marks on a line from t = 0 to the present and
// in a list, with a Rewind button that sends `rewind` with the chosen checkpoint's tick. The
// button is a panel button like the others (data-op / data-value), so the panel's one click
// handler sends it and shows the hub's answer; a view that only watches shows the timeline
// without it.

const SHIFT = 0.005;   // the present moved by more than this share of itself: place the marks again

function timeText(seconds) {
  return `t = ${Number(seconds.toFixed(3))} s`;
}

export class Timeline {
  constructor(box) {
    this.box = box;
    this.ticks = [];
    this.rate = 1;
    this.present = 0;       // plant s at the line's right end
    this.control = false;
    const head = document.createElement('div');
    head.className = 'timeline-head';
    this.note = document.createElement('span');
    this.note.className = 'muted';
    this.note.id = 'timeline-note';
    head.append('Checkpoints ', this.note);
    this.track = document.createElement('div');
    this.track.className = 'timeline-track';
    this.track.id = 'timeline-track';
    this.track.addEventListener('click', (e) => {
      const mark = e.target.closest('.mark');
      if (mark) this._choose(mark.dataset.tick);
    });
    this.select = document.createElement('select');
    this.select.id = 'rewind-to';
    this.select.title = 'the checkpoint to go back to';
    this.select.addEventListener('change', () => this._choose(this.select.value));
    this.button = document.createElement('button');
    Object.assign(this.button, { type: 'button', id: 'rewind', textContent: 'Rewind' });
    this.button.title = 'put the run back to this checkpoint; it goes on from there (recorded in commands.csv)';
    this.button.dataset.op = 'rewind';
    const row = document.createElement('div');
    row.className = 'controls';
    row.append(this.select, this.button);
    box.replaceChildren(head, this.track, row);
    this._render();
  }

  /** The hub's checkpoints message: {tick, time, rate, checkpoints: [tick, …]}. */
  update(m) {
    const rate = Number(m.rate);
    this.rate = Number.isFinite(rate) && rate > 0 ? rate : this.rate;
    this.ticks = (Array.isArray(m.checkpoints) ? m.checkpoints : []).filter(Number.isInteger).sort((a, b) => a - b);
    this.present = Math.max(Number(m.time) || 0, this._last());
    this._render();
  }

  /** The page's plant time (s): the line's right end. It goes back with a rewind. */
  now(time) {
    const present = Math.max(time, this._last());
    if (Math.abs(present - this.present) <= SHIFT * Math.max(this.present, 1e-9)) return;
    this.present = present;
    this._place();
  }

  /** A view that may send commands shows the Rewind button; one that only watches, not. */
  setControl(control) {
    this.control = !!control;
    this.button.hidden = !this.control;
    this.button.disabled = !this.control || !this.ticks.length;
  }

  _last() {
    return this.ticks.length ? this.ticks[this.ticks.length - 1] / this.rate : 0;
  }

  _render() {
    const chosen = this.select.value;
    this.note.textContent = this.ticks.length ? `${this.ticks.length}, the last at ${timeText(this._last())}`
      : 'none yet (--checkpoint-every, --checkpoint-at, a checkpoint command)';
    this.track.replaceChildren(...this.ticks.map((tick) => {
      const mark = document.createElement('i');
      mark.className = 'mark';
      mark.dataset.tick = String(tick);
      mark.title = `${timeText(tick / this.rate)} (tick ${tick})`;
      return mark;
    }));
    // Newest first: going back a little is the usual wish.
    this.select.replaceChildren(...[...this.ticks].reverse().map((tick) => {
      const option = document.createElement('option');
      option.value = String(tick);
      option.textContent = `${timeText(tick / this.rate)} (tick ${tick})`;
      return option;
    }));
    this._choose(this.ticks.includes(Number(chosen)) ? chosen : this.select.value);
    this._place();
    this.setControl(this.control);
  }

  _choose(tick) {
    if (tick === undefined || tick === '') {
      delete this.button.dataset.value;
      return;
    }
    this.select.value = String(tick);
    this.button.dataset.value = String(Number(tick));
    for (const mark of this.track.children) mark.classList.toggle('chosen', mark.dataset.tick === String(tick));
  }

  _place() {
    const span = this.present > 0 ? this.present : 1;
    for (const mark of this.track.children) {
      mark.style.left = `${Math.min(100, (100 * Number(mark.dataset.tick)) / this.rate / span)}%`;
    }
  }
}
