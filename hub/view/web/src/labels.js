// Name tags on the 3D plant: one per belt (each belt of a switch its own), sensor and switch blade
// or gate, named after its object and placed above it, drawn as HTML over the canvas (crisp at any zoom, no font textures). Off
// by default — a plant of a hundred parts is a wall of names — and turned on with the Labels box.

import * as THREE from 'three';

/** The kinds of scene item that get a tag, and what the tag says each is. */
export const TAGGED = { belt: 'belt', trigger: 'sensor', part: 'switch blade or gate' };
const ABOVE = 0.06;   // m above the part's top

export class Labels {
  /** @param {HTMLElement} layer the box over the canvas the tags go in */
  constructor(layer) {
    this.layer = layer;
    this.tags = [];         // {object, kind, anchor: Vector3, element}
    this.visible = false;
    this._v = new THREE.Vector3();
  }

  /** The tags of a plant (scene.js PlantScene): one per object and tagged kind. */
  setPlant(plant) {
    const boxes = new Map();
    plant.root.updateMatrixWorld(true);
    plant.root.traverse((o) => {
      const d = o.userData;
      if (!o.isMesh || !d?.object || !(d.kind in TAGGED)) return;
      const key = `${d.kind}\u0000${d.object}\u0000${d.kind === 'belt' ? d.field ?? '' : ''}`;
      if (!boxes.has(key)) boxes.set(key, { object: d.object, kind: d.kind, box: new THREE.Box3() });
      boxes.get(key).box.expandByObject(o);
    });
    this.tags = [...boxes.values()].map(({ object, kind, box }) => {
      const centre = box.getCenter(new THREE.Vector3());
      const anchor = centre.clone();
      anchor.z = box.max.z + ABOVE;
      if (kind === 'belt') {   // a quarter of the way along: a switch's blade sits at its main belt's middle
        const size = box.getSize(new THREE.Vector3());
        if (size.x >= size.y) anchor.x -= size.x / 4;
        else anchor.y -= size.y / 4;
      }
      const element = document.createElement('span');
      element.className = `tag ${kind}`;
      element.dataset.object = object;
      element.dataset.kind = kind;
      element.textContent = object;
      element.title = `${object}: ${TAGGED[kind]}`;
      return { object, kind, anchor, centre, element };
    });
    this.layer.replaceChildren(...this.tags.map((t) => t.element));
    this.layer.hidden = !this.visible;
  }

  clear() {
    this.tags = [];
    this.layer.replaceChildren();
  }

  show(on) {
    this.visible = !!on;
    this.layer.hidden = !this.visible;
  }

  /** Per frame, while shown: each tag where its part is on screen (hidden behind the camera). */
  update(camera, width, height) {
    if (!this.visible) return;
    for (const t of this.tags) {
      const p = this._v.copy(t.anchor).project(camera);
      const off = p.z > 1 || p.z < -1 || Math.abs(p.x) > 1.05 || Math.abs(p.y) > 1.05;
      t.element.hidden = off;
      if (!off) t.element.style.transform = `translate(${((p.x + 1) / 2) * width}px, ${((1 - p.y) / 2) * height}px) translate(-50%, -100%)`;
    }
  }

  /** What the test hook reports: the tags shown now, {object, kind, at: [x, y]} with `at` where
   * the part's centre is on the page (client px), for a pointer to hover it. */
  shown(camera, canvas) {
    if (!this.visible) return [];
    const rect = canvas.getBoundingClientRect();
    return this.tags.filter((t) => !t.element.hidden).map((t) => {
      const p = this._v.copy(t.centre).project(camera);
      return { object: t.object, kind: t.kind, text: t.element.textContent,
        at: [rect.left + ((p.x + 1) / 2) * rect.width, rect.top + ((1 - p.y) / 2) * rect.height] };
    });
  }
}
