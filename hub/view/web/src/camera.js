// The camera: orbit, pan and zoom about a target (OrbitControls, z up as in the plant), framing
// the plant when a scene comes, and a follow mode that carries camera and target along with one
// bottle so the user keeps the angle and distance they chose. When the bottle leaves the plant
// (delivered, taken out: no longer in the bodies drawn) the camera lets go where it is, after
// LET_GO s without it — a bottle is missing from a frame or two while samples are sparse — and
// says so (`onLost`), instead of staying locked on a bottle that will not come back.

import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

const LET_GO = 0.5;   // s of wall time the followed bottle may be missing before the camera lets go

export class CameraRig {
  constructor(canvas, onLost = () => {}) {
    this.onLost = onLost;          // (id) => void: the followed bottle left, the camera let go
    this.camera = new THREE.PerspectiveCamera(45, 1, 0.01, 500);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(-3, -4, 3);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.enableDamping = true;
    this.controls.dampingFactor = 0.12;
    this.controls.screenSpacePanning = true;
    this.following = null;          // body id, or null
    this._last = null;              // the followed body's position at the last frame
    this._missing = null;           // wall time (s) the followed body was first missing, or null
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
    this._missing = null;
  }

  /** Per frame: `positionOf(id)` the drawn position of the followed body (undefined: not in play);
   * `now` wall time in s; `drawing`: whether any sample is drawn (no let-go before the first). */
  update(positionOf, now = performance.now() / 1000, drawing = true) {
    if (this.following) {
      const p = positionOf(this.following);
      if (!p && drawing) {
        this._missing ??= now;
        if (now - this._missing >= LET_GO) {
          const id = this.following;
          this.follow(null);   // the camera stays where it is, free to orbit again
          this.onLost(id);
        }
      } else if (p) this._missing = null;
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
