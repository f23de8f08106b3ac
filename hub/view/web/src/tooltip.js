// Hover and click in the 3D view: a tooltip naming the bottle under the pointer (id,
// destination, filled/capped) or the plant object a part belongs to; a click on a bottle (a
// press that did not drag the camera) picks it for the camera to follow.

import * as THREE from 'three';

const CLICK_SLOP = 5;   // px a press may move and still be a click, not an orbit

export class Picker {
  /**
   * @param {HTMLElement} element  the canvas
   * @param {HTMLElement} tip      the tooltip box
   * @param {{camera: () => THREE.Camera, targets: () => {bottles, bottleMesh, plant, objects},
   *          onPick: (id: string) => void}} hooks
   */
  constructor(element, tip, hooks) {
    this.element = element;
    this.tip = tip;
    this.hooks = hooks;
    this.raycaster = new THREE.Raycaster();
    this.pointer = null;      // last pointer position over the canvas, client px
    this.down = null;
    element.addEventListener('pointermove', (e) => { this.pointer = { x: e.clientX, y: e.clientY }; });
    element.addEventListener('pointerleave', () => { this.pointer = null; this.tip.hidden = true; });
    element.addEventListener('pointerdown', (e) => { this.down = { x: e.clientX, y: e.clientY }; });
    element.addEventListener('pointerup', (e) => this._click(e));
  }

  _hit(x, y) {
    const t = this.hooks.targets();
    if (!t) return null;
    const rect = this.element.getBoundingClientRect();
    const ndc = new THREE.Vector2(((x - rect.left) / rect.width) * 2 - 1, -((y - rect.top) / rect.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.hooks.camera());
    const bottle = this.raycaster.intersectObject(t.bottleMesh, false)[0];
    const hits = this.raycaster.intersectObject(t.plant, true).filter((h) => ownerOf(h.object));
    const other = hits[0];
    // A sensor volume is see-through: a bottle inside it is what the pointer means.
    const blocker = hits.find((h) => ownerOf(h.object).kind !== 'trigger');
    if (bottle && (!blocker || bottle.distance <= blocker.distance)) {
      const d = t.bottles.instance(bottle.instanceId);
      if (d) return { bottle: d };
    }
    if (other) return { item: ownerOf(other.object), objects: t.objects };
    return null;
  }

  _click(e) {
    const d = this.down;
    this.down = null;
    if (!d || Math.hypot(e.clientX - d.x, e.clientY - d.y) > CLICK_SLOP) return;
    const hit = this._hit(e.clientX, e.clientY);
    if (hit?.bottle) this.hooks.onPick(hit.bottle.id);
  }

  /** Per frame, while the pointer is over the view: things move under a still pointer too. */
  update() {
    if (!this.pointer || this.down) {
      if (this.down) this.tip.hidden = true;
      return;
    }
    const hit = this._hit(this.pointer.x, this.pointer.y);
    if (!hit) {
      this.tip.hidden = true;
      return;
    }
    this.tip.replaceChildren(...(hit.bottle ? bottleLines(hit.bottle) : itemLines(hit.item, hit.objects)));
    const rect = this.element.getBoundingClientRect();
    this.tip.style.left = `${this.pointer.x - rect.left + 14}px`;
    this.tip.style.top = `${this.pointer.y - rect.top + 14}px`;
    this.tip.hidden = false;
  }
}

/** The userData {object, kind} of a mesh or of the nearest parent that has one. */
function ownerOf(o) {
  for (let n = o; n; n = n.parent) if (n.userData?.object) return n.userData;
  return null;
}

function line(label, value) {
  const div = document.createElement('div');
  const b = document.createElement('b');
  b.textContent = label;
  div.append(b, ` ${value}`);
  return div;
}

function bottleLines(d) {
  const filled = (d.flags & 1) !== 0, capped = (d.flags & 2) !== 0;
  return [
    line('bottle', d.id),
    line('destination', d.destination || '—'),
    line('filled', filled ? 'yes' : 'no'),
    line('capped', capped ? 'yes' : 'no'),
  ];
}

const KINDS = { box: 'frame or rail', support: 'support', belt: 'belt', part: 'blade or gate',
  moving: 'moving part', trigger: 'sensor volume', arm: 'robot arm' };

function itemLines(item, objects) {
  const module = objects?.[item.object]?.module;
  const kind = document.createElement('div');
  kind.textContent = KINDS[item.kind] ?? item.kind;
  return [line(item.object, module ? `(${module})` : ''), kind];
}
