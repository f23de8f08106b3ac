// The bodies message (schemas/scene.schema.json `bodies_message`): a msgpack map whose arrays arrive as byte strings. Decoded
// here once into typed arrays, so the rest of the view never sees bytes.

import { decode } from '@msgpack/msgpack';

const EMPTY = new Uint8Array(0);

/**
 * A typed view of a byte string. msgpack hands out sub-arrays of the frame at any offset, and a
 * Float32Array/Uint16Array must start at a multiple of its element size: copy when it does not.
 * The wire is little-endian, as is every platform a browser runs on (x86, ARM), so no swap.
 */
function typed(bytes, Type) {
  if (!(bytes instanceof Uint8Array)) return new Type(0);
  const size = Type.BYTES_PER_ELEMENT;
  const length = Math.floor(bytes.byteLength / size);
  if (bytes.byteOffset % size === 0) return new Type(bytes.buffer, bytes.byteOffset, length);
  return new Type(bytes.slice(0, length * size).buffer);
}

function u8(bytes) {
  return bytes instanceof Uint8Array ? bytes : EMPTY;
}

/**
 * @typedef {object} BodiesSample
 * @property {number} tick
 * @property {number} time          plant time, s
 * @property {Uint16Array} rows     body rows in play
 * @property {Float32Array} poses   7 per row: x y z qx qy qz qw
 * @property {Uint8Array} flags     per row: bit 0 filled, bit 1 capped
 * @property {string[]} destinations per row, "" when none
 * @property {Uint8Array} parts     per part number: 1 solid
 * @property {Float32Array} moving  per moving part: offset along its axis, m
 * @property {Uint8Array} triggers  per trigger: 1 occupied
 * @property {Float32Array} arms    7 per arm: joint angles, rad
 */

/** @returns {BodiesSample} */
export function decodeBodies(buffer) {
  const m = decode(new Uint8Array(buffer));
  if (!m || typeof m !== 'object') throw new Error('bodies message: not a map');
  const rows = typed(m.rows, Uint16Array);
  const poses = typed(m.poses, Float32Array);
  if (poses.length < rows.length * 7) throw new Error(`bodies message: ${rows.length} rows but ${poses.length / 7} poses`);
  return {
    tick: Number(m.tick ?? 0),
    time: Number(m.time ?? 0),
    rows,
    poses,
    flags: u8(m.flags),
    destinations: Array.isArray(m.destinations) ? m.destinations : [],
    parts: u8(m.parts),
    moving: typed(m.moving, Float32Array),
    triggers: u8(m.triggers),
    arms: typed(m.arms, Float32Array),
  };
}
