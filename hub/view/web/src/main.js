// planthub view in the browser: wires the socket's messages to the parts of the page and runs
// the render loop. Each part is its own module; this file only routes and schedules.

import './style.css';
import { Connection, socketUrl } from './connection.js';
import { decodeBodies } from './bodiesmsg.js';
import { Playback } from './playback.js';
import { Stage } from './stage.js';
import { PlantScene } from './scene.js';
import { Bottles, BOTTLE_STATES, HIGHLIGHT_COLOUR } from './bodies.js';
import { PLANT_LEGEND } from './scene.js';
import { Labels } from './labels.js';
import { ExercisePanel } from './exercise.js';
import { FaultsPanel } from './faults.js';
import { Arms } from './arm.js';
import { Panel } from './panel.js';
import { Figures, formatNumber } from './figures.js';
import { Plots } from './plots.js';
import { PlayBar } from './playbar.js';
import { RecordedPlots } from './recorded.js';
import { EventLog } from './events.js';
import { Picker } from './tooltip.js';
import { installHooks } from './hooks.js';

const FOLLOW_LIST_MS = 1000;   // how often the follow list is refreshed from the bodies in play
const DEFAULT_PERIOD = '0.05'; // the hub's bodies period unless asked otherwise (schemas/scene.schema.json `bodies_message`)

class App {
  constructor() {
    this.$ = (sel) => document.querySelector(sel);
    this.hooks = installHooks(() => this.bottles?.positions() ?? {});
    this.stage = new Stage(this.$('#viewport'));
    if (!this.stage.renderer) this._viewportMessage('This browser has no WebGL: the 3D view is off, the rest works.');
    this.playback = new Playback();
    this.plant = null;
    this.bottles = null;
    this.arms = null;
    this.panel = new Panel(this.$('#panel'), (m) => this.connection.send(m));
    this.faults = new FaultsPanel(this.$('#faults-box'), (m) => this.connection.send(m));
    this.exercise = new ExercisePanel(this.$('#exercise-box'));
    this.labels = new Labels(this.$('#tags'));
    this.hooks.labels = () => this.labels.shown(this.stage.rig.camera, this.stage.canvas);
    this.stage.rig.onLost = (id) => this._lost(id);
    this.figures = new Figures(this.$('#figures'));
    this.plots = new Plots(this.$('#plots'));
    this.recorded = new RecordedPlots(this.$('#recorded'));
    this.playbar = new PlayBar(this.$('#playback-bar'), (m) => this.connection.send(m));
    this.mode = 'live';       // hello's mode: 'playback' for a recorded run (`planthub view RUN_DIR`)
    this.events = new EventLog(document);
    this.hooks.events = this.events.rows;
    this.picker = new Picker(this.stage.canvas, this.$('#tooltip'), {
      camera: () => this.stage.rig.camera,
      targets: () => this.plant && this.bottles &&
        { bottles: this.bottles, bottleMesh: this.bottles.mesh, plant: this.plant.root, objects: this.plant.doc.objects },
      onPick: (id) => this._follow(id),
    });
    this._legend();
    this._cameraBar();
    this.connection = new Connection(socketUrl(window.location), {
      onOpen: () => this._connected(true),
      onClose: () => this._connected(false),
      onMessage: (m) => this._message(m),
      onBinary: (data) => this._bodies(data),
    });
    this.connection.open();
    this._last = performance.now();
    this._shown = null;
    requestAnimationFrame((t) => this._frame(t));
    setInterval(() => this._refreshFollowList(), FOLLOW_LIST_MS);
  }

  // ---- messages -------------------------------------------------------------------------

  _message(m) {
    const handler = {
      hello: () => this._hello(m),
      scene: () => this._scene(m.scene),
      state: () => this._state(m),
      figures: () => this._figures(m),
      events: () => this._events(m),
      result: () => this._result(m),
      faults: () => this._faults(m),
      checkpoints: () => this._checkpoints(m),
      slots: () => this.plots.slots(m),
      playback: () => this._playbackState(m),
      recording: () => this.recorded.set(m),
      error: () => this._error(m),
    }[m.type];
    if (handler) handler();   // unknown types: a newer server; ignore, as the spec says for keys
  }

  _hello(m) {
    this.hooks.hello = m;
    this.$('#run-name').textContent = m.run ?? '—';
    document.title = `planthub view — ${m.run ?? ''}`;
    this.panel.setControl(m.control === true, m.reason);
    // The role is the view server's: a trainee's page is never sent a fault (hub/view/server.py).
    const role = m.role === 'trainee' ? 'trainee' : m.mode === 'playback' ? 'playback' : 'instructor';
    document.body.dataset.role = role;
    this.faults.setRole(role);
    const badge = this.$('#role');
    badge.hidden = role === 'playback';
    badge.textContent = role;
    badge.title = role === 'trainee' ? `a trainee's view: ${m.role_reason ?? ''}` : 'an instructor\'s view: it sees and injects faults';
    this.mode = m.mode === 'playback' ? 'playback' : 'live';
    if (this.mode === 'playback') {
      this.playbar.show(m);
      this.plots.recordedRun();
      this.hooks.playback = { time: Number(m.start ?? 0), playing: false, speed: 1 };
    }
  }

  /** A recorded run's playback clock changed: a seek (or a start again) is a jump, never interpolated. */
  _playbackState(m) {
    this.playbar.state(m);
    if (m.jump) {
      this.playback.jump();
      this._shown = null;
    }
    this.playback.setPace(Number(m.speed ?? 1));
    if (this.hooks.playback) Object.assign(this.hooks.playback, { playing: !!m.playing, speed: Number(m.speed ?? 1) });
  }

  _events(m) {
    if (m.reset) this.events.reset();
    this.events.add(m.rows);
  }

  _scene(doc) {
    if (!doc || typeof doc !== 'object') return;
    const first = !this.plant;
    this._dropScene();
    this.hooks.scene = doc;
    this.plant = new PlantScene(doc);
    this.bottles = new Bottles(doc.bodies ?? []);
    this.plant.root.add(this.bottles.mesh);
    this.arms = new Arms(this.plant.arms, this.plant.root);
    this.stage.scene.add(this.plant.root);
    this.labels.setPlant(this.plant);
    const box = this.plant.bounds();
    this.stage.floor(box);
    if (first) this.stage.rig.fit(box);
    this.panel.setObjects(doc.objects);
    this.plots.setScene(doc);
    this.events.setScene(doc);
    // The samples stay: a scene fetched again mid-run (or while paused, when no new sample
    // comes) draws the bodies at once; a new run's samples reset the playback by their time.
    this._shown = null;
    this._highlight(this.stage.rig.following);
  }

  _dropScene() {
    if (!this.plant) return;
    this.stage.scene.remove(this.plant.root);
    this.bottles.dispose();
    this.plant.dispose();
    this.labels.clear();
    this.plant = this.bottles = this.arms = null;
  }

  _state(m) {
    const { type, ...state } = m;
    this.hooks.state = state;
    const badge = this.$('#run-state');
    badge.textContent = state.state ?? '—';
    badge.className = `badge ${state.state ?? ''}`;
    badge.title = state.reason ? `${state.state}: ${state.reason}` : 'state of the run';
  }

  _figures(m) {
    const { type, ...figures } = m;
    this.hooks.figures = figures;
    const { exercise, ...others } = figures.sections ?? {};
    this.figures.update({ ...figures, sections: others });
    if (exercise) {
      this.exercise.update(exercise, figures.ended || figures.final || this.hooks.state?.state === 'stopped');
      this.hooks.exercise = this.exercise.last;
    }
    this.$('#figures-final').hidden = !figures.final;
    if (!figures.final) this.plots.figures(figures);
  }

  _result(m) {
    const { type, ...result } = m;
    this.hooks.results.push(result);
    if (result.op === 'fault' || result.op === 'repair') this.faults.result(result);
    else this.panel.result(result);
  }

  /** The view's refusal of a command (or of a playback request): said where it was asked. */
  _error(m) {
    if (m.op === 'fault' || m.op === 'repair') {
      this.hooks.results.push({ ...m, ok: false });
      this.faults.result({ ...m, ok: false });
    } else if (this.mode === 'playback') this.playbar.refused(m);
    else if (m.op) this.panel.result({ ...m, ok: false });
  }

  /** The run's checkpoints: the panel's timeline, each one a rewind may go back to. */
  _checkpoints(m) {
    const { type, ...timeline } = m;
    this.hooks.checkpoints = timeline;
    this.panel.checkpoints(timeline);
  }

  _faults(m) {
    const { type, ...board } = m;
    this.hooks.faults = board;
    this.faults.update(board);
  }

  /** The followed bottle left the plant: the camera let go of it (camera.js). */
  _lost(id) {
    this._highlight(null);
    this._refreshFollowList();
    this.$('#follow').value = '';
    const note = this.$('#camera-note');
    note.textContent = `${id} left the plant: the camera let go`;
    note.hidden = false;
    clearTimeout(this._noteTimer);
    this._noteTimer = setTimeout(() => { note.hidden = true; }, 4000);
    this.hooks.lost.push(id);
  }

  _bodies(data) {
    let sample;
    try {
      sample = decodeBodies(data);
    } catch (err) {
      console.warn('planthub view: bad bodies message', err);
      return;
    }
    this.hooks.tick = sample.tick;
    this.$('#clock').textContent = `t = ${formatNumber(sample.time)} s`;
    this.hooks.time = sample.time;
    this.panel.now(sample.time);
    this.playback.push(sample, performance.now() / 1000);
  }

  _connected(on) {
    this.hooks.connected = on;
    const badge = this.$('#connection');
    badge.textContent = on ? 'connected' : 'reconnecting';
    badge.className = `badge ${on ? 'on' : 'off'}`;
    if (on) {
      const period = this.$('#rate').value;
      if (period !== DEFAULT_PERIOD) this.connection.send({ type: 'rate', period: Number(period) });
    } else {
      // Until a hello says otherwise, nobody is there to take a command.
      this.panel.setControl(false, 'not connected to the view server');
    }
  }

  // ---- the render loop ------------------------------------------------------------------

  _frame(now) {
    requestAnimationFrame((t) => this._frame(t));
    const dt = Math.min(0.25, Math.max(0, (now - this._last) / 1000));   // a hidden tab: no huge jump
    this._last = now;
    const t = this.playback.advance(now / 1000, dt);
    if (this.plant && t !== null) this._draw(t);
    if (this.mode === 'playback' && t !== null) {
      this.playbar.update(t);
      this.recorded.mark(t);
      this.hooks.playback.time = t;
    }
    this.stage.rig.update((id) => this.bottles?.find(id)?.position, now / 1000, t !== null && !!this.bottles);
    this.picker.update();
    this.labels.update(this.stage.rig.camera, this.stage.canvas.clientWidth, this.stage.canvas.clientHeight);
    if (this.stage.render()) this.hooks.frames++;
  }

  /** The plant at playback time t: bodies, parts, moving offsets, triggers, arms, belt stripes. */
  _draw(t) {
    const { a, b, f } = this.playback.bracket(t);
    this.bottles.update(a, b, f);
    const moving = Array.from(a.moving, (x, n) => (n < b.moving.length ? x + (b.moving[n] - x) * f : x));
    this.plant.applyState(a, moving);
    this.arms.update(a, b, f);
    // Stripes move with played-back plant time, so they stop when the run is paused.
    const played = this._shown === null ? 0 : Math.max(0, t - this._shown);
    this._shown = t;
    this.plant.scrollBelts(played, (object) => this.plots.speedOf(object));
  }

  // ---- page furniture -------------------------------------------------------------------

  /** Every kind of thing drawn: the bottles by state, the followed one, and the plant's parts. */
  _legend() {
    const box = this.$('#legend');
    const entry = (colour, label, data) => {
      const item = document.createElement('span');
      Object.assign(item.dataset, data);
      const swatch = document.createElement('i');
      swatch.style.background = `#${colour.toString(16).padStart(6, '0')}`;
      item.append(swatch, label);
      return item;
    };
    box.replaceChildren(
      ...BOTTLE_STATES.map((s) => entry(s.colour, s.label, { state: s.key })),
      entry(HIGHLIGHT_COLOUR, 'followed bottle', { state: 'followed' }),
      ...PLANT_LEGEND.map((p) => entry(p.colour, p.label, { kind: p.key })),
    );
  }

  _cameraBar() {
    this.$('#follow').addEventListener('change', (e) => this._follow(e.target.value));
    this.$('#labels').addEventListener('change', (e) => this.labels.show(e.target.checked));
    this.$('#fit').addEventListener('click', () => {
      this._follow('');
      if (this.plant) this.stage.rig.fit(this.plant.bounds());
    });
    this.$('#rate').addEventListener('change', (e) => this.connection.send({ type: 'rate', period: Number(e.target.value) }));
  }

  _follow(id) {
    this.stage.rig.follow(id);
    this._highlight(id);
    this._refreshFollowList();
    this.$('#follow').value = id || '';
  }

  /** Draw the followed bottle in its own colour, so it is found again after a turn of the camera. */
  _highlight(id) {
    if (this.bottles) this.bottles.highlight = id ? this.bottles.byRow.find((b) => b && b.id === id)?.row ?? null : null;
  }

  /** The follow list: the bottles in play now, plus the one followed even when it has left. */
  _refreshFollowList() {
    const select = this.$('#follow');
    const ids = new Set((this.bottles?.drawn ?? []).map((d) => d.id));
    const following = this.stage.rig.following;
    if (following) ids.add(following);
    const wanted = ['', ...[...ids].sort((x, y) => x.localeCompare(y, undefined, { numeric: true }))];
    const have = [...select.options].map((o) => o.value);
    if (wanted.length === have.length && wanted.every((v, i) => v === have[i])) return;
    select.replaceChildren(...wanted.map((v) => {
      const o = document.createElement('option');
      o.value = v;
      o.textContent = v || '— none —';
      return o;
    }));
    select.value = following ?? '';
  }

  _viewportMessage(text) {
    const box = this.$('#viewport-message');
    box.textContent = text;
    box.hidden = false;
  }
}

if (document.readyState === 'loading') window.addEventListener('DOMContentLoaded', () => new App());
else new App();
