// The camera: orbit, pan and zoom about a target (OrbitControls, z up as in the plant), framing
// the plant when a scene comes, and a follow mode that carries camera and target along with one
// bottle so the user keeps the angle and distance they chose.

import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

export class CameraRig {
  constructor(canvas) {
    this.camera = new THREE.PerspectiveCamera(45, 1, 0.01, 500);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(-3, -4, 3);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = true;
    this.controls.dampingFactor = 0.12;
    this.controls.screenSpacePanning = true;
    this.following = null;          // body id, or null
    this._last = null;              // the followed body's position at the last frame
  }

  resize(width, height) {
    this.camera.aspect = width / Math.max(1, height);
    this.camera.updateProjectionMatrix();
  }

  /** Look at the whole of `box` from the front left, a little above. */
  fit(box) {
    if (box.isEmpty()) return;
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    const radius = Math.max(sphere.radius, 0.25);
    // The narrower of the two fields of view decides: a wide plant in a tall window still fits.
    const vertical = THREE.MathUtils.degToRad(this.camera.fov);
    const horizontal = 2 * Math.atan(Math.tan(vertical / 2) * this.camera.aspect);
    const distance = radius / Math.sin(Math.min(vertical, horizontal) / 2);
    // A plant is flat: seen from above at an angle the sphere overstates it, so come closer.
    const direction = new THREE.Vector3(-0.15, -0.7, 0.95).normalize();
    this.camera.position.copy(sphere.center).addScaledVector(direction, distance * 0.9);
    this.camera.near = Math.max(0.005, distance / 1000);
    this.camera.far = distance * 20;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(sphere.center);
    this.controls.maxDistance = distance * 8;
    this.controls.update();
  }

  follow(id) {
    this.following = id || null;
    this._last = null;
  }

  /** Per frame: `positionOf(id)` the drawn position of the followed body (undefined: not in play). */
  update(positionOf) {
    if (this.following) {
      const p = positionOf(this.following);
      if (p) {
        if (this._last) {
          const delta = p.clone().sub(this._last);
          this.camera.position.add(delta);
          this.controls.target.add(delta);
        } else {
          // First frame of following: look at the bottle from where we are, a bit closer.
          const offset = this.camera.position.clone().sub(this.controls.target);
          offset.setLength(Math.min(offset.length(), 1.2));
          this.controls.target.copy(p);
          this.camera.position.copy(p).add(offset);
        }
        this._last = p.clone();
      }
    }
    this.controls.update();
  }
}
