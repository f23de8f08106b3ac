// The plant's geometry from the scene document (schemas/scene.schema.json `scene`): one three.js group in plant
// coordinates (z up), with handles on what the bodies message changes — part solidity, moving
// part offsets, trigger occupancy, belt surfaces — so a sample is applied without searching.

import * as THREE from 'three';
import { boxMesh, slabMesh, beltStripGeometry } from './shapes.js';

const BELT_LIFT = 0.001;      // m above the support, so the belt does not flicker into it
const STRIPE_PERIOD = 0.05;   // m between the belt's cross stripes (they move with the belt)

const COLOURS = {
  support: 0xb9bec4,
  box: 0x8a9099,
  part: 0xe07a1f,
  moving: 0x4f79b8,
  trigger: 0xf2d24b,
  triggerOn: 0xff4538,
  belt: 0x3a4048,
  arm: 0x888888,
};

/** The legend of what the plant is drawn with: every kind of scene item (and a sensor's two looks). */
export const PLANT_LEGEND = [
  { key: 'belt', label: 'belt', colour: COLOURS.belt },
  { key: 'support', label: 'support', colour: COLOURS.support },
  { key: 'box', label: 'frame or rail', colour: COLOURS.box },
  { key: 'part', label: 'switch blade or gate', colour: COLOURS.part },
  { key: 'moving', label: 'moving part', colour: COLOURS.moving },
  { key: 'trigger', label: 'sensor', colour: COLOURS.trigger },
  { key: 'triggerOn', label: 'sensor sees a bottle', colour: COLOURS.triggerOn },
  { key: 'arm', label: 'robot arm', colour: COLOURS.arm },
];

/** Stripes across the belt, made once; each belt gets a clone to scroll at its own speed. */
function stripeTexture() {
  const canvas = document.createElement('canvas');
  canvas.width = 32;
  canvas.height = 4;
  const g = canvas.getContext('2d');
  g.fillStyle = '#3a4048';
  g.fillRect(0, 0, 32, 4);
  g.fillStyle = '#262a30';
  g.fillRect(0, 0, 8, 4);
  const texture = new THREE.CanvasTexture(canvas);
  texture.wrapS = THREE.RepeatWrapping;
  texture.colorSpace = THREE.SRGBColorSpace;
  texture.repeat.set(1 / STRIPE_PERIOD, 1);
  return texture;
}

function tag(mesh, item) {
  mesh.userData = { object: item.object, kind: item.kind, field: item.field };
  return mesh;
}

export class PlantScene {
  /** @param {object} doc the scene document */
  constructor(doc) {
    this.doc = doc;
    this.root = new THREE.Group();
    this.root.name = 'plant';
    this.parts = [];      // part number → materials to switch between solid and faint
    this.moving = [];     // moving number → {group, axis}
    this.triggers = [];   // trigger number → materials
    this.belts = [];      // {object, field, texture}
    this.arms = [];       // the "arm" items, for arm.js
    this.pickables = [];  // meshes a hover can name
    this.stripes = stripeTexture();
    for (const item of doc.items ?? []) this._add(item);
  }

  _add(item) {
    const build = {
      box: () => this._box(item),
      support: () => this._support(item),
      belt: () => this._belt(item),
      part: () => this._part(item),
      moving: () => this._moving(item),
      trigger: () => this._trigger(item),
      arm: () => this.arms.push(item),
    }[item.kind];
    if (build) build();
    else console.warn(`planthub view: scene item of unknown kind "${item.kind}" ignored`);
  }

  _mesh(mesh, item, parent = this.root) {
    parent.add(tag(mesh, item));
    this.pickables.push(mesh);
    return mesh;
  }

  _box(item) {
    this._mesh(boxMesh(item, new THREE.MeshStandardMaterial({ color: COLOURS.box, metalness: 0.3, roughness: 0.6 })), item);
  }

  _support(item) {
    const material = new THREE.MeshStandardMaterial({ color: COLOURS.support, roughness: 0.9 });
    this._mesh(slabMesh(item.rect, item.z, item.thickness ?? 0.02, material), item);
  }

  _belt(item) {
    const texture = this.stripes.clone();
    texture.needsUpdate = true;
    const material = new THREE.MeshStandardMaterial({ map: texture, roughness: 0.8, side: THREE.DoubleSide });
    const geometry = beltStripGeometry(item.line, item.half_width, item.z + BELT_LIFT);
    this._mesh(new THREE.Mesh(geometry, material), item);
    this.belts.push({ object: item.object, field: item.field, texture });
  }

  _part(item) {
    const material = new THREE.MeshStandardMaterial({ color: COLOURS.part, transparent: true, roughness: 0.5 });
    for (const box of item.boxes ?? []) this._mesh(boxMesh(box, material), item);
    (this.parts[item.part] ??= []).push(material);
    this._setSolid(material, true);
  }

  _moving(item) {
    const group = new THREE.Group();
    const material = new THREE.MeshStandardMaterial({ color: COLOURS.moving, metalness: 0.4, roughness: 0.4 });
    for (const box of item.boxes ?? []) this._mesh(boxMesh(box, material), item, group);
    this.root.add(group);
    this.moving[item.moving] = { group, axis: new THREE.Vector3(...item.axis) };
  }

  _trigger(item) {
    const material = new THREE.MeshStandardMaterial({
      color: COLOURS.trigger, transparent: true, opacity: 0.18, depthWrite: false,
      emissive: COLOURS.triggerOn, emissiveIntensity: 0,
    });
    const mesh = this._mesh(boxMesh(item, material), item);
    mesh.renderOrder = 2;   // after the opaque geometry, so what is inside shows through
    (this.triggers[item.trigger] ??= []).push(material);
  }

  _setSolid(material, solid) {
    material.opacity = solid ? 1.0 : 0.15;
    material.depthWrite = solid;
  }

  /** Apply the discrete and offset state of one bodies sample (and moving offsets `moving`). */
  applyState(sample, moving) {
    this.parts.forEach((materials, n) => {
      const solid = (sample.parts[n] ?? 1) === 1;
      for (const m of materials) this._setSolid(m, solid);
    });
    this.moving.forEach((part, n) => {
      if (part) part.group.position.copy(part.axis).multiplyScalar(moving[n] ?? 0);
    });
    this.triggers.forEach((materials, n) => {
      const on = sample.triggers[n] === 1;
      for (const m of materials) {
        m.color.setHex(on ? COLOURS.triggerOn : COLOURS.trigger);
        m.emissiveIntensity = on ? 0.8 : 0;
        m.opacity = on ? 0.55 : 0.18;
      }
    });
  }

  /** Scroll the belts' stripes; `speedOf(object)` gives the belt's speed in m/s or undefined. */
  scrollBelts(dt, speedOf) {
    for (const belt of this.belts) {
      const v = speedOf(belt.object);
      if (typeof v === 'number' && Number.isFinite(v)) belt.texture.offset.x -= (v * dt) / STRIPE_PERIOD;
    }
  }

  bounds() {
    return new THREE.Box3().setFromObject(this.root);
  }

  dispose() {
    this.root.traverse((o) => {
      if (o.isMesh) {
        if (o.geometry.type !== 'BoxGeometry') o.geometry.dispose();
        o.material.dispose?.();
        o.material.map?.dispose?.();
      }
    });
    this.stripes.dispose();
  }
}
