// The bottles: one instanced cylinder for every body of the scene, so a hundred bottles are one
// draw call. Each frame draws the rows in play at the playback time: positions lerped and
// orientations slerped between the two samples around it, colour by filled/capped.

import * as THREE from 'three';
import { unitCylinder } from './shapes.js';

export const BOTTLE_STATES = [
  { key: 'empty', label: 'empty', colour: 0x9fd3f0 },
  { key: 'filled', label: 'filled', colour: 0xf0a23a },
  { key: 'capped', label: 'filled + capped', colour: 0x3fae5a },
];

/** The state's index in BOTTLE_STATES from the flags byte (bit 0 filled, bit 1 capped). */
export function bottleState(flags) {
  if (flags & 2) return 2;   // a cap is what a viewer looks for: capped shows as capped
  return flags & 1 ? 1 : 0;
}

const COLOURS = BOTTLE_STATES.map((s) => new THREE.Color(s.colour));
export const HIGHLIGHT_COLOUR = 0xff3df0;   // the followed bottle
const HIGHLIGHT = new THREE.Color(HIGHLIGHT_COLOUR);

export class Bottles {
  /** @param {Array<{row, id, object, radius, height}>} bodies the scene's bodies */
  constructor(bodies) {
    this.byRow = [];
    for (const b of bodies) this.byRow[b.row] = b;
    const capacity = Math.max(1, bodies.length);
    const material = new THREE.MeshStandardMaterial({ roughness: 0.35, metalness: 0.05 });
    this.mesh = new THREE.InstancedMesh(unitCylinder(), material, capacity);
    this.mesh.instanceMatrix.setUsage(THREE.DynamicDrawUsage);
    this.mesh.count = 0;
    this.mesh.frustumCulled = false;   // instances move anywhere; the group's bounds would be stale
    this.mesh.name = 'bottles';
    // Per drawn instance: which row, its state and destination (for hover, follow and the hooks).
    this.drawn = [];       // instance → {row, id, position: Vector3, flags, destination}
    this.highlight = null; // row followed: drawn in another colour
    this._slot = new Int32Array(this.byRow.length).fill(-1);
    this._p = new THREE.Vector3();
    this._pb = new THREE.Vector3();
    this._q = new THREE.Quaternion();
    this._qb = new THREE.Quaternion();
    this._s = new THREE.Vector3();
    this._m = new THREE.Matrix4();
    // Colour buffer made up front: three.js sizes its shader once, before the first colour.
    this.mesh.setColorAt(0, COLOURS[0]);
  }

  /**
   * Draw the rows of sample `a` (the one at or before the playback time — a body that left
   * between a and b is drawn until b's time, one that appeared in b from then on), moved a
   * fraction `f` of the way to their pose in `b`.
   */
  update(a, b, f) {
    const slot = this._slot;
    if (b !== a) for (let i = 0; i < b.rows.length; i++) slot[b.rows[i]] = i;
    const drawn = this.drawn;
    drawn.length = 0;
    let n = 0;
    for (let i = 0; i < a.rows.length; i++) {
      const row = a.rows[i];
      const body = this.byRow[row];
      if (!body) continue;       // a row the scene does not know: a newer scene will come
      const pa = a.poses, o = 7 * i;
      this._p.set(pa[o], pa[o + 1], pa[o + 2]);
      this._q.set(pa[o + 3], pa[o + 4], pa[o + 5], pa[o + 6]);
      const j = b !== a ? slot[row] : -1;
      if (j >= 0 && f > 0) {
        const pb = b.poses, k = 7 * j;
        this._pb.set(pb[k], pb[k + 1], pb[k + 2]);
        this._qb.set(pb[k + 3], pb[k + 4], pb[k + 5], pb[k + 6]);
        this._p.lerp(this._pb, f);
        this._q.slerp(this._qb, f);
      }
      this._q.normalize();
      this._s.set(body.radius, body.radius, body.height);
      this._m.compose(this._p, this._q, this._s);
      this.mesh.setMatrixAt(n, this._m);
      const flags = a.flags[i] ?? 0;
      this.mesh.setColorAt(n, row === this.highlight ? HIGHLIGHT : COLOURS[bottleState(flags)]);
      drawn.push({ row, id: body.id, position: this._p.clone(), flags, destination: a.destinations[i] ?? '' });
      n++;
    }
    if (b !== a) for (let i = 0; i < b.rows.length; i++) slot[b.rows[i]] = -1;
    this.mesh.count = n;
    this.mesh.instanceMatrix.needsUpdate = true;
    if (this.mesh.instanceColor) this.mesh.instanceColor.needsUpdate = true;
    this.mesh.computeBoundingSphere();
  }

  hideAll() {
    this.mesh.count = 0;
    this.drawn.length = 0;
  }

  /** The drawn instance `index` (from a raycast's instanceId), or undefined. */
  instance(index) {
    return this.drawn[index];
  }

  /** The drawn body with id `id`, or undefined. */
  find(id) {
    return this.drawn.find((d) => d.id === id);
  }

  /** {"<id>": [x, y, z]} of what is drawn now (the test hook). */
  positions() {
    const out = {};
    for (const d of this.drawn) out[d.id] = [d.position.x, d.position.y, d.position.z];
    return out;
  }

  dispose() {
    this.mesh.geometry.dispose();
    this.mesh.material.dispose();
    this.mesh.dispose();
  }
}
