// The operator panel, generic over the scene's object slots (hub/view/frames.py): which
// buttons an object gets follows from its slots' names, types and directions, not from its
// module, so a new module with a `<comp>.run` or `<comp>.closed` slot gets its controls for free.
// Every button says what it sends in data-op / data-slot / data-value (JSON), which is also
// what the one click handler reads — the markup is the contract.

import { Timeline } from './timeline.js';

const RESULTS_SHOWN = 4;

/** The control rules: slot → label and buttons [text, op, value]. */
const RULES = [
  { // a belt's drive (or any component's run/stop)
    match: (comp, name, type, dir) => name === 'run' && type === 'bool' && dir === 'target',
    label: (comp) => comp,
    buttons: [['Stop', 'force', false], ['Start', 'force', true], ['Auto', 'release', null]],
  },
  { // a sensor's occupancy
    match: (comp, name, type, dir) => comp === 'trigger' && name === 'occupied' && type === 'bool' && dir === 'source',
    label: () => 'sensor',
    buttons: [['Force on', 'force', true], ['Force off', 'force', false], ['Release', 'release', null]],
  },
  { // a switch's blade
    match: (comp, name, type, dir) => comp === 'blade' && name === 'working' && type === 'bool' && dir === 'target',
    label: () => 'blade',
    buttons: [['Working', 'force', true], ['Base', 'force', false], ['Release', 'release', null]],
  },
  { // a gate: separator, stopper
    match: (comp, name, type, dir) => name === 'closed' && type === 'bool' && dir === 'target',
    label: (comp) => comp,
    buttons: [['Close', 'force', true], ['Open', 'force', false], ['Release', 'release', null]],
  },
];

function button(text, attrs, id) {
  const b = document.createElement('button');
  b.type = 'button';
  b.textContent = text;
  if (id) b.id = id;
  for (const [k, v] of Object.entries(attrs)) if (v !== undefined) b.dataset[k] = v;
  return b;
}

/** The controls of one object: [{slot, label, rule}] for the slots a rule matches. */
export function objectControls(name, object) {
  const out = [];
  for (const [slot, type, direction] of object.slots ?? []) {
    const [comp, ...rest] = slot.split('.');
    const slotName = rest.join('.');
    const rule = RULES.find((r) => r.match(comp, slotName, type, direction));
    if (rule) out.push({ slot: `${name}.${slot}`, label: rule.label(comp), rule });
  }
  return out;
}

export class Panel {
  /** @param {(msg: object) => boolean} send  puts a message on the socket; false if closed */
  constructor(root, send) {
    this.root = root;
    this.send = send;
    this.runSlots = [];      // every `<comp>.run` slot: what the emergency stop forces off
    this.control = false;
    this.reason = 'not connected';
    this.results = root.querySelector('#panel-result');
    this.reasonBox = root.querySelector('#panel-reason');
    this._buildRunControls(root.querySelector('#run-controls'));
    this.objectsBox = root.querySelector('#object-controls');
    this.timeline = new Timeline(root.querySelector('#timeline'));
    root.addEventListener('click', (e) => this._click(e));
    this.setControl(false, this.reason);
  }

  _buildRunControls(box) {
    const pace = document.createElement('input');
    Object.assign(pace, { type: 'number', id: 'pace-value', min: '0.1', step: '0.5', value: '1' });
    pace.title = 'factor of real time (runs started with --realtime)';
    const paceButton = button('Pace', { op: 'pace', value: '1' }, 'pace');
    pace.addEventListener('input', () => {
      const v = Number(pace.value);
      if (Number.isFinite(v) && v > 0) paceButton.dataset.value = JSON.stringify(v);
    });
    box.replaceChildren(
      button('Emergency stop', {}, 'estop'),
      button('Reset', {}, 'reset'),
      button('Pause', { op: 'pause', value: 'null' }, 'run-pause'),
      button('Resume', { op: 'resume', value: 'null' }, 'run-resume'),
      button('Step', { op: 'step', value: '1' }, 'step'),
      pace, paceButton,
    );
    box.querySelector('#estop').classList.add('danger');
  }

  /** Rebuild the object controls for a scene's objects. */
  setObjects(objects) {
    this.runSlots = [];
    const rows = [];
    for (const [name, object] of Object.entries(objects ?? {}).sort(([a], [b]) => a.localeCompare(b))) {
      const controls = objectControls(name, object);
      if (!controls.length) continue;
      const row = document.createElement('div');
      row.className = 'object-row';
      const title = document.createElement('div');
      title.className = 'object-name';
      title.textContent = name;
      title.title = object.module ?? '';
      const groups = document.createElement('div');
      groups.className = 'slot-groups';
      row.append(title, groups);
      for (const c of controls) {
        if (c.rule === RULES[0]) this.runSlots.push(c.slot);
        const group = document.createElement('span');
        group.className = 'slot-group';
        group.title = c.slot;
        const label = document.createElement('span');
        label.className = 'slot-label';
        label.textContent = c.label;
        group.append(label, ...c.rule.buttons.map(([text, op, value]) =>
          button(text, { op, slot: c.slot, value: JSON.stringify(value) })));
        groups.append(group);
      }
      rows.push(row);
    }
    const estop = this.root.querySelector('#estop');
    estop.dataset.slots = this.runSlots.join(' ');
    this.root.querySelector('#reset').dataset.slots = this.runSlots.join(' ');
    this.objectsBox.replaceChildren(...rows);
    this.setControl(this.control, this.reason);
  }

  /** Enable the panel, or disable every control and say why (hello's control/reason). */
  setControl(control, reason) {
    this.control = !!control;
    this.reason = reason ?? '';
    for (const el of this.root.querySelectorAll('button, input')) el.disabled = !this.control;
    this.reasonBox.hidden = this.control;
    this.reasonBox.textContent = this.control ? '' : (this.reason || 'control is not allowed');
    this.timeline.setControl(this.control);
  }

  /** The checkpoints a rewind may go back to (the hub's `checkpoints` message). */
  checkpoints(m) {
    this.timeline.update(m);
  }

  /** The plant time drawn (s), for the timeline's present. */
  now(time) {
    this.timeline.now(time);
  }

  _click(e) {
    const b = e.target.closest('button');
    if (!b || b.disabled) return;
    if (b.id === 'estop') return this._all('force', false);
    if (b.id === 'reset') return this._all('release', null);
    if (!b.dataset.op) return;
    this._command(b.dataset.op, b.dataset.slot, JSON.parse(b.dataset.value ?? 'null'));
    if (b.dataset.slot) this._mark(b);
  }

  /** The emergency stop and its reset: one command per run slot. */
  _all(op, value) {
    for (const slot of this.runSlots) this._command(op, slot, value);
    for (const b of this.objectsBox.querySelectorAll('button.chosen')) b.classList.remove('chosen');
    if (op === 'force') {
      for (const slot of this.runSlots) {
        this.objectsBox.querySelector(`button[data-op="force"][data-slot="${CSS.escape(slot)}"][data-value="false"]`)?.classList.add('chosen');
      }
    }
  }

  _command(op, slot, value) {
    const message = { type: 'command', op };
    if (slot) message.slot = slot;
    if (value !== null && value !== undefined) message.value = value;
    if (!this.send(message)) this._say(`not sent (no connection): ${op} ${slot ?? ''}`, true);
  }

  /** Show which mode a slot was last put in (forced on/off or released). */
  _mark(b) {
    const group = b.closest('.slot-group');
    if (!group) return;
    for (const other of group.querySelectorAll('button')) other.classList.toggle('chosen', other === b && b.dataset.op !== 'release');
  }

  /** A command result from the hub. */
  result(r) {
    const id = r.id !== undefined && r.id !== null ? `${r.id}: ` : '';
    if (r.ok) this._say(`${id}ok at tick ${r.tick ?? '?'}`, false);
    else this._say(`${id}refused: ${r.error ?? 'no reason given'}`, true);
  }

  /** The last few results, newest first: an emergency stop answers once per belt. */
  _say(text, bad) {
    const line = document.createElement('div');
    line.textContent = text;
    if (bad) line.className = 'bad';
    this.results.prepend(line);
    while (this.results.childElementCount > RESULTS_SHOWN) this.results.lastElementChild.remove();
  }
}
