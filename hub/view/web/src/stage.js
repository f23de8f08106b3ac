// The 3D stage: renderer, lights, floor grid and camera rig in the viewport element, sized to
// it. The plant, bottles and arms are put on it per scene document.

import * as THREE from 'three';
import { CameraRig } from './camera.js';

const FLOOR_BELOW = 0.02;   // m under the lowest geometry: the grid must not cut through supports

export class Stage {
  constructor(container) {
    this.container = container;
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xeef1f4);
    this.renderer = makeRenderer();
    const canvas = this.renderer?.domElement ?? document.createElement('canvas');
    container.prepend(canvas);
    this.canvas = canvas;
    this.rig = new CameraRig(canvas);
    this._lights();
    this.grid = null;
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  _lights() {
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8d8a84, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.8);
    sun.position.set(-3, -5, 8);   // high, from the front left: the side rails shade the belts a little
    this.scene.add(sun);
  }

  /** Put a grid on the floor under `box` (the plant's bounds), replacing the old one. */
  floor(box) {
    if (this.grid) {
      this.scene.remove(this.grid);
      this.grid.geometry.dispose();
    }
    if (box.isEmpty()) return;
    const size = box.getSize(new THREE.Vector3());
    const span = Math.ceil(Math.max(size.x, size.y) + 2);
    this.grid = new THREE.GridHelper(span, span * 2, 0xb8bec6, 0xd6dadf);
    this.grid.rotation.x = Math.PI / 2;   // GridHelper lies in x-z; the plant's floor is x-y
    const centre = box.getCenter(new THREE.Vector3());
    this.grid.position.set(Math.round(centre.x), Math.round(centre.y), box.min.z - FLOOR_BELOW);
    this.scene.add(this.grid);
  }

  resize() {
    const w = this.container.clientWidth, h = this.container.clientHeight;
    this.renderer?.setSize(w, h, false);
    this.canvas.style.width = '100%';
    this.canvas.style.height = '100%';
    this.rig.resize(w, h);
  }

  /** Draw a frame; false when there is no WebGL (nothing drawn). */
  render() {
    if (!this.renderer) return false;
    this.renderer.render(this.scene, this.rig.camera);
    return true;
  }
}

/** A WebGL renderer, or null where the browser has no WebGL (the page still connects and counts). */
function makeRenderer() {
  try {
    const renderer = new THREE.WebGLRenderer({ antialias: true });
    renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    return renderer;
  } catch (err) {
    console.error('planthub view: no WebGL', err);
    return null;
  }
}
