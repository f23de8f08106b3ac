// Robot arms: the scene's "arm" items loaded with urdf-loader from the view server's
// /pybullet_data/ (the same URDF the engine loads), placed at their base and yaw, joint angles
// from the bodies message's "arms" (7 per arm, in the item's `joints` order).

import * as THREE from 'three';
import URDFLoader from 'urdf-loader';
import { OBJLoader } from 'three/examples/jsm/loaders/OBJLoader.js';

const JOINTS_PER_ARM = 7;   // the bodies message's stride (schemas/scene.schema.json `bodies_message`)
const TOOL_RADIUS = 0.012;

/**
 * pybullet_data's arms mostly ship Wavefront meshes, which urdf-loader's own mesh loader does
 * not read (it knows STL and COLLADA): OBJ goes through OBJLoader, coloured with the URDF's
 * material; everything else takes the default path.
 */
function loadMesh(loader, path, manager, material, done) {
  if (!/\.obj$/i.test(path)) {
    loader.defaultMeshLoader(path, manager, material, done);
    return;
  }
  new OBJLoader(manager).load(path, (group) => {
    group.traverse((o) => {
      if (o.isMesh) o.material = material ?? new THREE.MeshPhongMaterial({ color: 0x888888 });
    });
    done(group);
  }, undefined, (err) => done(null, err));
}

class Arm {
  constructor(item, parent) {
    this.item = item;
    this.robot = null;
    this.pending = null;
    this.group = new THREE.Group();
    this.group.name = `arm ${item.object}`;
    this.group.userData = { object: item.object, kind: 'arm' };   // hover names what is below it
    this.group.position.set(...item.base);
    this.group.rotation.z = item.yaw ?? 0;
    parent.add(this.group);
    this._load();
  }

  _load() {
    const loader = new URDFLoader();
    loader.loadMeshCb = (...args) => loadMesh(loader, ...args);
    loader.load(`/pybullet_data/${this.item.urdf}`, (robot) => {
      this.robot = robot;
      this._addTool();
      this.group.add(robot);
      if (this.pending) this.setJoints(this.pending);
    }, undefined, (err) => console.warn(`planthub view: arm ${this.item.object}: ${err.message ?? err}`));
  }

  /** The tool the engine puts on the last link: a rod along its z axis, `tool_length` long. */
  _addTool() {
    const last = this.robot.joints[this.item.joints.at(-1)];
    const link = last?.children.find((c) => c.isURDFLink);
    const length = this.item.tool_length ?? 0;
    if (!link || !(length > 0)) return;
    const geometry = new THREE.CylinderGeometry(TOOL_RADIUS, TOOL_RADIUS, length, 12);
    geometry.rotateX(Math.PI / 2);
    const tool = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: 0x555a60, metalness: 0.6 }));
    tool.position.z = length / 2;
    link.add(tool);
  }

  /** @param {ArrayLike<number>} angles this arm's joint angles, rad */
  setJoints(angles) {
    if (!this.robot) {
      this.pending = Array.from(angles);
      return;
    }
    this.item.joints.forEach((name, i) => {
      if (i < angles.length) this.robot.setJointValue(name, angles[i]);
    });
  }
}

export class Arms {
  /** @param {object[]} items the scene's "arm" items */
  constructor(items, parent) {
    this.arms = [];
    for (const item of items) this.arms[item.arm] = new Arm(item, parent);
  }

  /** Joint angles from the "arms" arrays of two samples, a fraction f from a to b. */
  update(a, b, f) {
    this.arms.forEach((arm, n) => {
      if (!arm) return;
      const o = JOINTS_PER_ARM * n;
      if (a.arms.length < o + JOINTS_PER_ARM) return;
      const angles = new Array(JOINTS_PER_ARM);
      for (let i = 0; i < JOINTS_PER_ARM; i++) {
        const qa = a.arms[o + i];
        const qb = b.arms.length >= o + JOINTS_PER_ARM ? b.arms[o + i] : qa;
        angles[i] = qa + (qb - qa) * f;
      }
      arm.setJoints(angles);
    });
  }
}
