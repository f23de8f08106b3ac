// Geometry for the scene's primitives, in plant coordinates (m, z up, yaw about +z).

import * as THREE from 'three';

const UNIT_BOX = new THREE.BoxGeometry(1, 1, 1);
const ARC_STEP = Math.PI / 48;      // rad per segment of a curved belt: smooth at any zoom we use

/** A mesh of the scene's box form {center, half_extents, yaw}; the unit box is shared, scaled. */
export function boxMesh(box, material) {
  const mesh = new THREE.Mesh(UNIT_BOX, material);
  const [hx, hy, hz] = box.half_extents;
  mesh.scale.set(2 * hx, 2 * hy, 2 * hz);
  mesh.position.set(...box.center);
  mesh.rotation.z = box.yaw ?? 0;
  return mesh;
}

/**
 * A support's slab: `rect` [x0, y0, x1, y1] with its top surface at `z`.
 */
export function slabMesh(rect, z, thickness, material) {
  const [x0, y0, x1, y1] = rect;
  const t = Math.max(thickness, 1e-3);
  return boxMesh({
    center: [(x0 + x1) / 2, (y0 + y1) / 2, z - t / 2],
    half_extents: [Math.abs(x1 - x0) / 2, Math.abs(y1 - y0) / 2, t / 2],
    yaw: 0,
  }, material);
}

/**
 * The points of a belt's centre line with their unit left normals and arc length: the straight
 * line's two ends, or the arc sampled every ARC_STEP. {x, y, nx, ny, s}[]
 */
export function beltPath(line) {
  if (line.type === 'arc') {
    const [cx, cy] = line.center;
    const r = line.radius;
    const n = Math.max(2, Math.ceil(Math.abs(line.sweep) / ARC_STEP) + 1);
    const turn = Math.sign(line.sweep) || 1;
    const points = [];
    for (let i = 0; i < n; i++) {
      const a = line.start + (line.sweep * i) / (n - 1);
      const ux = Math.cos(a), uy = Math.sin(a);
      // Travelling counter-clockwise the left side is towards the centre; clockwise, away.
      points.push({ x: cx + r * ux, y: cy + r * uy, nx: -turn * ux, ny: -turn * uy,
                    s: r * Math.abs(line.sweep) * i / (n - 1) });
    }
    return points;
  }
  const [x0, y0] = line.start;
  const [x1, y1] = line.end;
  const length = Math.hypot(x1 - x0, y1 - y0) || 1e-9;
  const nx = -(y1 - y0) / length, ny = (x1 - x0) / length;
  return [{ x: x0, y: y0, nx, ny, s: 0 }, { x: x1, y: y1, nx, ny, s: length }];
}

/**
 * A belt's top surface: a strip `halfWidth` either side of its centre line at height z, with
 * u = arc length in m (so a repeating texture scrolls at the belt's speed) and v across.
 */
export function beltStripGeometry(line, halfWidth, z) {
  const path = beltPath(line);
  const positions = [], uvs = [], index = [];
  path.forEach((p, i) => {
    positions.push(p.x + p.nx * halfWidth, p.y + p.ny * halfWidth, z);   // left edge
    positions.push(p.x - p.nx * halfWidth, p.y - p.ny * halfWidth, z);   // right edge
    uvs.push(p.s, 1, p.s, 0);
    if (i > 0) {
      const l0 = 2 * (i - 1), r0 = l0 + 1, l1 = 2 * i, r1 = l1 + 1;
      index.push(r0, r1, l1, r0, l1, l0);
    }
  });
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  geometry.setAttribute('uv', new THREE.Float32BufferAttribute(uvs, 2));
  geometry.setIndex(index);
  geometry.computeVertexNormals();
  return geometry;
}

/** A unit cylinder along z (radius 1, height 1, centred), scaled per bottle. */
export function unitCylinder(segments = 20) {
  const g = new THREE.CylinderGeometry(1, 1, 1, segments, 1);
  g.rotateX(Math.PI / 2);
  return g;
}
