// The live plant summary from the figures message (schemas/scene.schema.json `figures_message`): the headline figures an
// operator watches — in, delivered per lane, misroutes, rejects, jams, on the line, pace — and
// then every other key PlantSummary.as_dict gives (and any other section), rendered generically,
// so a figure added on the hub side shows up without a change here.

const SHOWN = new Set(['bottles_in', 'placed', 'released', 'delivered', 'by_destination', 'sinks',
  'rejected', 'misrouted', 'on_line', 'most_on_line', 'throughput', 'jams', 'jam_after', 'window']);

export function formatNumber(v) {
  if (typeof v !== 'number') return String(v);
  if (Number.isInteger(v)) return String(v);
  const a = Math.abs(v);
  return v.toFixed(a >= 100 ? 1 : a >= 1 ? 2 : 3);
}

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  e.append(...children.filter((c) => c !== null && c !== undefined));
  return e;
}

function tile(label, value, note, key) {
  return el('div', { class: 'tile', 'data-figure': key },
    el('div', { class: 'tile-value' }, value), el('div', { class: 'tile-label' }, label),
    note ? el('div', { class: 'tile-note' }, note) : null);
}

/** Any JSON value as DOM: tables for arrays of maps, nested lists for maps. */
export function renderValue(v) {
  if (v === null || v === undefined) return el('span', { class: 'muted' }, '—');
  if (typeof v !== 'object') return document.createTextNode(formatNumber(v));
  if (Array.isArray(v)) {
    if (!v.length) return el('span', { class: 'muted' }, 'none');
    if (v.every((x) => x && typeof x === 'object' && !Array.isArray(x))) {
      const keys = [...new Set(v.flatMap((x) => Object.keys(x)))];
      return el('table', { class: 'generic' },
        el('thead', {}, el('tr', {}, ...keys.map((k) => el('th', {}, k)))),
        el('tbody', {}, ...v.map((x) => el('tr', {}, ...keys.map((k) => el('td', {}, renderValue(x[k])))))));
    }
    return document.createTextNode(v.map((x) => (typeof x === 'object' ? JSON.stringify(x) : formatNumber(x))).join(', '));
  }
  const entries = Object.entries(v);
  if (!entries.length) return el('span', { class: 'muted' }, 'none');
  return el('dl', { class: 'generic' }, ...entries.flatMap(([k, x]) => [el('dt', {}, k), el('dd', {}, renderValue(x))]));
}

/** Deliveries per lane: the sinks that are not reject sinks, with what each accepts. */
function lanes(plant) {
  const sinks = Object.entries(plant.sinks ?? {});
  if (!sinks.length) return null;
  const rows = sinks.map(([name, s]) => el('tr', { class: s.rejects ? 'reject' : '' },
    el('td', {}, name),
    el('td', {}, s.rejects ? 'rejects' : (s.accepts ?? ['any']).join(', ')),
    el('td', { class: 'num' }, formatNumber(s.total)),
    el('td', { class: 'num' + (s.misrouted ? ' bad' : '') }, formatNumber(s.misrouted))));
  return el('table', { class: 'lanes' },
    el('thead', {}, el('tr', {}, el('th', {}, 'sink'), el('th', {}, 'accepts'), el('th', {}, 'bottles'), el('th', {}, 'misrouted'))),
    el('tbody', {}, ...rows));
}

function count(list, none) {
  return list === null || list === undefined ? none : String(list.length);
}

function plantTiles(plant) {
  const released = Object.values(plant.released ?? {}).reduce((a, b) => a + b, 0);
  const through = plant.throughput ?? {};
  const most = plant.most_on_line;
  return el('div', { class: 'tiles' },
    tile('bottles in', formatNumber(plant.bottles_in ?? 0), `${plant.placed ?? 0} placed, ${released} released`, 'bottles_in'),
    tile('delivered', formatNumber(plant.delivered ?? 0), null, 'delivered'),
    tile('misrouted', count(plant.misrouted, '—'), plant.misrouted === null ? 'not judged' : null, 'misrouted'),
    tile('rejected', count(plant.rejected, '—'), plant.rejected === null ? 'no reject sink' : null, 'rejected'),
    tile('jams', count(plant.jams, '0'), plant.jam_after !== undefined ? `stuck ≥ ${formatNumber(plant.jam_after)} s` : null, 'jams'),
    tile('on the line', count(plant.on_line, '0'), most ? `most ${most.bottles} at ${formatNumber(most.time)} s` : null, 'on_line'),
    tile('per minute', through.per_minute !== undefined ? formatNumber(through.per_minute) : '—',
      through.first_to_last_per_minute ? `${formatNumber(through.first_to_last_per_minute)} first to last` : null, 'per_minute'));
}

function plantSection(plant) {
  const rest = Object.fromEntries(Object.entries(plant).filter(([k]) => !SHOWN.has(k)));
  const jams = plant.jams?.length ? el('details', { class: 'more', open: '' }, el('summary', {}, 'jams'), renderValue(plant.jams)) : null;
  const misrouted = plant.misrouted?.length ? el('details', { class: 'more' }, el('summary', {}, 'misrouted bottles'), renderValue(plant.misrouted)) : null;
  const rejected = plant.rejected?.length ? el('details', { class: 'more' }, el('summary', {}, 'rejected bottles'), renderValue(plant.rejected)) : null;
  return [
    plantTiles(plant),
    lanes(plant),
    el('details', { class: 'more' }, el('summary', {}, 'by destination'), renderValue(plant.by_destination)),
    jams, misrouted, rejected,
    el('details', { class: 'more' }, el('summary', {}, 'on the line'), renderValue(plant.on_line)),
    Object.keys(rest).length ? el('details', { class: 'more' }, el('summary', {}, 'more'), renderValue(rest)) : null,
  ];
}

export class Figures {
  constructor(box) {
    this.box = box;
    this.last = null;
  }

  /** @param {object} f the figures map {tick, time, wall, rtf, sections} */
  update(f) {
    this.last = f;
    // Keep the user's open/closed choice of the collapsible parts across updates.
    const open = new Map([...this.box.querySelectorAll('details')].map((d) => [d.firstChild?.textContent, d.open]));
    const head = el('div', { class: 'tiles run' },
      tile('plant time', `${formatNumber(f.time ?? 0)} s`, `tick ${f.tick ?? '—'}`, 'time'),
      tile('wall time', f.wall !== undefined ? `${formatNumber(f.wall)} s` : '—', null, 'wall'),
      tile('real-time factor', f.rtf !== undefined && f.rtf !== null ? `${formatNumber(f.rtf)}×` : '—', null, 'rtf'));
    const parts = [head];
    for (const [name, section] of Object.entries(f.sections ?? {})) {
      parts.push(el('h4', {}, name));
      if (name === 'plant' && section && typeof section === 'object') parts.push(...plantSection(section));
      else parts.push(renderValue(section));
    }
    this.box.replaceChildren(...parts.filter(Boolean));
    for (const d of this.box.querySelectorAll('details')) {
      const was = open.get(d.firstChild?.textContent);
      if (was !== undefined) d.open = was;
    }
  }
}
