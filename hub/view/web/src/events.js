// The event log: [tick, slot, detail] rows as the hub sends them (schemas/scene.schema.json `events_message`), newest on top,
// filtered by object name (the slot's first part). Every row is kept for the test hook and
// for changing the filter later; only the newest matching rows are in the table, since a
// busy plant makes thousands and the DOM is the slow part.

const KEEP = 100000;     // rows remembered
const SHOW = 400;        // rows in the table

function objectOf(slot) {
  return String(slot ?? '').split('.')[0];
}

function detailText(detail) {
  if (detail === null || detail === undefined || detail === '') return '';
  return typeof detail === 'object' ? JSON.stringify(detail) : String(detail);
}

export class EventLog {
  constructor(root) {
    this.rows = [];
    this.body = root.querySelector('#events tbody');
    this.filterInput = root.querySelector('#event-filter');
    this.names = root.querySelector('#event-objects');
    this.count = root.querySelector('#event-count');
    this.rate = 150;
    this.filterInput.addEventListener('input', () => this.render());
  }

  setScene(doc) {
    this.rate = doc.physics_rate || 150;
    this.names.replaceChildren(...Object.keys(doc.objects ?? {}).sort().map((name) => {
      const o = document.createElement('option');
      o.value = name;
      return o;
    }));
  }

  filter() {
    return this.filterInput.value.trim().toLowerCase();
  }

  _matches(row, f) {
    if (!f) return true;
    const obj = objectOf(row[1]).toLowerCase();
    return obj === f || obj.includes(f);
  }

  /** Forget every row (a recorded run played back from an earlier time). */
  reset() {
    this.rows.length = 0;   // the same array: the test hook holds it
    this.body.replaceChildren();
    this._count(this.filter());
  }

  add(rows) {
    if (!Array.isArray(rows) || !rows.length) return;
    for (const r of rows) this.rows.push(r);
    if (this.rows.length > KEEP) this.rows.splice(0, this.rows.length - KEEP);
    const f = this.filter();
    const fresh = rows.filter((r) => this._matches(r, f)).slice(-SHOW).reverse().map((r) => this._tr(r));
    this.body.prepend(...fresh);
    while (this.body.childElementCount > SHOW) this.body.lastElementChild.remove();
    this._count(f);
  }

  render() {
    const f = this.filter();
    const out = [];
    for (let i = this.rows.length - 1; i >= 0 && out.length < SHOW; i--) {
      if (this._matches(this.rows[i], f)) out.push(this._tr(this.rows[i]));
    }
    this.body.replaceChildren(...out);
    this._count(f);
  }

  _count(f) {
    this.count.textContent = f ? `showing “${f}”, ${this.rows.length} in all` : `${this.rows.length} events`;
  }

  _tr([tick, slot, detail]) {
    const tr = document.createElement('tr');
    tr.dataset.object = objectOf(slot);
    const t = document.createElement('td');
    t.textContent = String(tick);
    t.title = `${(Number(tick) / this.rate).toFixed(3)} s`;
    const s = document.createElement('td');
    s.textContent = String(slot);
    const d = document.createElement('td');
    d.textContent = detailText(detail);
    tr.append(t, s, d);
    return tr;
  }
}
