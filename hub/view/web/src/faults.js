// The instructor's faults panel (hub/view/frames.py `faults`, schemas/scene.schema.json
// `faults_message`): the scenario's faults and when, those in effect with a Repair button, and a
// form to inject one live — its kind, a target among the parts that kind fits (the hub's board
// says which), the kind's parameters and an optional duration. The hub checks it as it checks a
// scenario's fault and answers; a refusal is shown here. A trainee's page never gets a board, and
// this panel stays hidden.

const PARAMS = {   // kind → the inputs of its parameters: [key, label, kind of input, options]
  sensor_stuck: [['value', 'sees a bottle', 'select', [['true', 'always (on)'], ['false', 'never (off)']]]],
  belt_failure: [['speed', 'speed left (fraction)', 'number', { min: 0, max: 0.99, step: 0.05, value: 0 }]],
  reader_fault: [['reads', 'reads', 'select', [['nothing', 'nothing'], ['wrong', 'a wrong id']]],
    ['destination', 'destination (wrong)', 'text', {}]],
};

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) if (v !== undefined && v !== null) e.setAttribute(k, v);
  e.append(...children.filter((c) => c !== null && c !== undefined));
  return e;
}

function option(value, text) {
  const o = document.createElement('option');
  o.value = value;
  o.textContent = text ?? value;
  return o;
}

function describe(parameters) {
  const text = Object.entries(parameters ?? {}).map(([k, v]) => `${k} ${JSON.stringify(v)}`).join(', ');
  return text ? ` (${text})` : '';
}

export class FaultsPanel {
  /** @param {(msg: object) => boolean} send  puts a message on the socket; false if closed */
  constructor(box, send) {
    this.box = box;
    this.send = send;
    this.board = null;
    this.count = 0;
    this.kind = box.querySelector('#fault-kind');
    this.target = box.querySelector('#fault-target');
    this.params = box.querySelector('#fault-params');
    this.duration = box.querySelector('#fault-for');
    this.said = box.querySelector('#fault-result');
    this.kind.addEventListener('change', () => this._kindChanged());
    box.querySelector('#fault-inject').addEventListener('click', () => this._inject());
    box.addEventListener('click', (e) => {
      const b = e.target.closest('button[data-repair]');
      if (b) this._command('repair', b.dataset.target, { name: b.dataset.repair }, `repair:${b.dataset.repair}`);
    });
  }

  /** hello's role: the panel is an instructor's only. */
  setRole(role) {
    this.box.hidden = role !== 'instructor';
  }

  /** A faults message: the kinds and their targets, the scheduled faults, those in effect. */
  update(board) {
    const first = !this.board;
    this.board = board;
    if (first) {
      const kinds = Object.entries(board.kinds ?? {}).filter(([, k]) => (k.targets ?? []).length);
      this.kind.replaceChildren(...kinds.map(([name, k]) => { const o = option(name); o.title = k.what; return o; }));
      this._kindChanged();
    }
    const scheduled = (board.scheduled ?? []).map((f) => el('li', { 'data-fault': f.name, 'data-state': f.state },
      el('b', {}, f.name), ` ${f.kind} at ${f.target}${describe(f.parameters)}, ${f.when} `,
      el('span', { class: `badge ${f.state}` }, f.state)));
    this.box.querySelector('#faults-scheduled').replaceChildren(
      ...(scheduled.length ? scheduled : [el('li', { class: 'muted' }, 'none in the scenario')]));
    const active = (board.active ?? []).map((f) => {
      const repair = el('button', { type: 'button', 'data-repair': f.name, 'data-target': f.target }, 'Repair');
      const until = f.until !== null && f.until !== undefined ? `, until ${f.until} s` : '';
      return el('li', { 'data-fault': f.name }, el('b', {}, f.name), ` ${f.kind} at ${f.target}${describe(f.parameters)}${until} `,
        repair);
    });
    this.box.querySelector('#faults-active').replaceChildren(
      ...(active.length ? active : [el('li', { class: 'muted' }, 'none in effect')]));
  }

  _kindChanged() {
    const kind = this.kind.value;
    const targets = this.board?.kinds?.[kind]?.targets ?? [];
    this.target.replaceChildren(...targets.map((t) => option(t)));
    this.params.replaceChildren(...(PARAMS[kind] ?? []).map(([key, label, type, extra]) => {
      let input;
      if (type === 'select') {
        input = el('select', { 'data-param': key });
        input.append(...extra.map(([v, t]) => option(v, t)));
      } else {
        input = el('input', { 'data-param': key, type, ...extra });
      }
      return el('label', {}, `${label} `, input);
    }));
  }

  /** The fault the form describes, sent to the hub (which checks it and answers). */
  _inject() {
    const kind = this.kind.value, target = this.target.value;
    if (!kind || !target) return this._say('choose a kind and a target', true);
    this.count += 1;
    const value = { name: `live ${this.count}: ${kind} ${target}`, kind };
    for (const input of this.params.querySelectorAll('[data-param]')) {
      const key = input.dataset.param;
      if (key === 'value') value.value = input.value === 'true';
      else if (key === 'speed') value.speed = Number(input.value);
      else if (key === 'destination') { if (value.reads === 'wrong') value.destination = input.value; }
      else value[key] = input.value;
    }
    const lasts = this.duration.value.trim();
    if (lasts !== '') value.for = Number(lasts);
    this._command('fault', target, value, `inject:${this.count}`);
  }

  _command(op, slot, value, ref) {
    if (!this.send({ type: 'command', op, slot, value, ref })) this._say(`not sent (no connection): ${op}`, true);
  }

  /** The hub's answer to one of this panel's commands, or the view's refusal. */
  result(r) {
    const what = `${r.op ?? ''} ${r.ref ?? ''}`.trim();
    if (r.ok) this._say(`${what}: ok at tick ${r.tick ?? '?'}`, false);
    else this._say(`${what}: refused: ${r.error ?? 'no reason given'}`, true);
  }

  _say(text, bad) {
    this.said.textContent = text;
    this.said.className = bad ? 'bad' : 'muted';
  }
}
