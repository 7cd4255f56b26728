/**
 * The 3D view's logic without three.js: the cell file's scene section, joint states to joint values, the URDF's
 * joints (names, limits, mimic), markers (visualization_msgs/MarkerArray) to shapes, staleness and camera presets.
 * The cell frame is ROS's: x forward, y left, z up (the view keeps it; its camera's up is +z).
 */

import { m } from '$lib/paraglide/messages.js';
import { fmtFixed, fmtNumber } from '../../core/i18n.js';
import { TfTree, baseToPose, compose, frameId } from './tf.js';

export const JOINT_STATE_TYPE = 'sensor_msgs/JointState';
export const MARKERS_TYPE = 'visualization_msgs/MarkerArray';

/**
 * One arm of the view, as GET /api/config gives it (bff/src/features/scene).
 * @typedef {{ group: string, joints: string[], joint_states: string, base: number[], base_frame: string | null, urdf_url: string }} SceneArm
 * @typedef {{ markers: string | null, fixed_frame: string | null, stale_after_s: number, arms: SceneArm[] }} SceneSection
 * fixed_frame: the TF frame the view draws in (null: no TF); base_frame: the TF frame that places the arm's base
 */

/**
 * The section with every field in shape (a missing or odd field gets its default).
 * @param {any} section
 * @returns {SceneSection}
 */
export function sceneSection(section) {
  const arms = Array.isArray(section?.arms) ? section.arms : [];
  return {
    markers: typeof section?.markers === 'string' && section.markers ? section.markers : null,
    fixed_frame: typeof section?.fixed_frame === 'string' && section.fixed_frame ? section.fixed_frame : null,
    stale_after_s: Number(section?.stale_after_s) > 0 ? Number(section.stale_after_s) : 1,
    arms: arms
      .filter((/** @type {any} */ a) => a && typeof a.group === 'string' && typeof a.urdf_url === 'string')
      .map((/** @type {any} */ a) => ({
        group: a.group,
        joints: Array.isArray(a.joints) ? a.joints.map(String) : [],
        joint_states: typeof a.joint_states === 'string' ? a.joint_states : '/joint_states',
        base: [0, 1, 2, 3].map((i) => (Number.isFinite(Number(a.base?.[i])) ? Number(a.base[i]) : 0)),
        base_frame: typeof a.base_frame === 'string' && a.base_frame && typeof section?.fixed_frame === 'string' ? a.base_frame : null,
        urdf_url: a.urdf_url,
      })),
  };
}

/**
 * The group's joint values in a sensor_msgs/JointState (other arms' joints on the same topic are left out).
 * @param {any} msg
 * @param {string[]} joints
 * @returns {Record<string, number> | null}  null: none of the group's joints is in the message
 */
export function pickJoints(msg, joints) {
  const names = Array.isArray(msg?.name) ? msg.name : [];
  const pos = msg?.position;
  /** @type {Record<string, number>} */
  const out = {};
  let found = 0;
  names.forEach((/** @type {string} */ n, /** @type {number} */ i) => {
    const v = Number(pos?.[i]);
    if (joints.includes(n) && Number.isFinite(v)) {
      out[n] = v;
      found++;
    }
  });
  return found ? out : null;
}

/**
 * @typedef {{ name: string, type: string, lower: number | null, upper: number | null,
 *   mimic: { joint: string, multiplier: number, offset: number } | null }} JointInfo
 */

/**
 * The movable joints of a URDF, read from its text (what the view moves; fixed joints are left out).
 * @param {Document} doc  the parsed URDF
 * @returns {JointInfo[]}
 */
export function urdfJoints(doc) {
  /** @type {JointInfo[]} */
  const out = [];
  const robot = doc.documentElement;
  for (const j of Array.from(robot.children).filter((c) => c.tagName === 'joint')) {
    const type = j.getAttribute('type') ?? 'fixed';
    if (type === 'fixed' || type === 'floating' || type === 'planar') continue;
    const limit = Array.from(j.children).find((c) => c.tagName === 'limit');
    const mimic = Array.from(j.children).find((c) => c.tagName === 'mimic');
    const num = (/** @type {string | null | undefined} */ s, /** @type {number | null} */ d) => (s == null || s === '' || !Number.isFinite(Number(s)) ? d : Number(s));
    out.push({
      name: j.getAttribute('name') ?? '',
      type,
      lower: type === 'continuous' ? null : num(limit?.getAttribute('lower'), null),
      upper: type === 'continuous' ? null : num(limit?.getAttribute('upper'), null),
      mimic: mimic ? { joint: mimic.getAttribute('joint') ?? '', multiplier: num(mimic.getAttribute('multiplier'), 1) ?? 1, offset: num(mimic.getAttribute('offset'), 0) ?? 0 } : null,
    });
  }
  return out;
}

/**
 * Parse a URDF text; throws an Error saying what is wrong (not XML, not a <robot>).
 * @param {string} text
 * @returns {Document}
 */
export function parseUrdf(text) {
  const doc = new DOMParser().parseFromString(text, 'application/xml');
  const err = doc.getElementsByTagName('parsererror')[0];
  if (err) throw new Error(m.scene_urdf_not_xml({ detail: (err.textContent ?? '').trim().split('\n')[0].slice(0, 160) }));
  if (doc.documentElement?.tagName !== 'robot') throw new Error(m.scene_urdf_root({ tag: String(doc.documentElement?.tagName) }));
  return doc;
}

/**
 * The group's joint names the URDF does not move (a cell file that does not match its URDF).
 * @param {JointInfo[]} joints  urdfJoints()
 * @param {string[]} names  the group's joint names (the cell file's, as on /joint_states)
 */
export function missingJoints(joints, names) {
  const have = new Set(joints.filter((j) => !j.mimic).map((j) => j.name));
  return names.filter((n) => !have.has(n));
}

/**
 * The value each mimic joint follows to (URDF: value = multiplier * leader + offset).
 * @param {JointInfo[]} joints
 * @param {Record<string, number>} values  leader values
 * @returns {Record<string, number>}
 */
export function mimicValues(joints, values) {
  /** @type {Record<string, number>} */
  const out = {};
  for (const j of joints) if (j.mimic && j.mimic.joint in values) out[j.name] = j.mimic.multiplier * values[j.mimic.joint] + j.mimic.offset;
  return out;
}

/**
 * Joint states older than the cell's limit (or none yet) make the arm stale.
 * @param {number | null} at  when the last joint state arrived (ms)
 * @param {number} now
 * @param {number} staleAfterS
 * @returns {{ stale: boolean, ageS: number | null }}
 */
export function staleness(at, now, staleAfterS) {
  if (at == null) return { stale: true, ageS: null };
  const ageS = Math.max(0, now - at) / 1000;
  return { stale: ageS > staleAfterS, ageS };
}

/** @param {number | null} ageS */
export const staleText = (ageS) =>
  ageS == null ? m.scene_no_joint_states() : m.scene_stale({ age: ageS < 10 ? fmtFixed(ageS, 1) : fmtNumber(Math.round(ageS)) });

// visualization_msgs/Marker types and actions this view draws.
export const MARKER = { CUBE: 1, SPHERE: 2, CYLINDER: 3, ADD: 0, DELETE: 2, DELETEALL: 3 };
/** @type {Record<number, 'cube' | 'sphere' | 'cylinder'>} */
const SHAPES = { [MARKER.CUBE]: 'cube', [MARKER.SPHERE]: 'sphere', [MARKER.CYLINDER]: 'cylinder' };

/**
 * @typedef {{ key: string, shape: 'cube' | 'sphere' | 'cylinder', position: number[], quaternion: number[],
 *   scale: number[], color: number[], frame: string }} Shape  quaternion x, y, z, w; color r, g, b, a in 0..1;
 *   frame: its header's frame_id (its pose is in that frame)
 */

/**
 * Apply a MarkerArray to the shapes shown (by ns/id, as RViz does): ADD/MODIFY replace, DELETE removes one,
 * DELETEALL removes all (of its ns when it has one). Types other than cube, sphere and cylinder are counted, not drawn.
 * @param {Map<string, Shape>} shapes  changed in place
 * @param {any} msg
 * @returns {{ skipped: number }}
 */
export function applyMarkers(shapes, msg) {
  let skipped = 0;
  for (const m of Array.isArray(msg?.markers) ? msg.markers : []) {
    const key = `${m.ns ?? ''}/${m.id ?? 0}`;
    const action = Number(m.action ?? 0);
    if (action === MARKER.DELETEALL) {
      for (const k of [...shapes.keys()]) if (!m.ns || k.startsWith(`${m.ns}/`)) shapes.delete(k);
      continue;
    }
    if (action === MARKER.DELETE) {
      shapes.delete(key);
      continue;
    }
    const shape = SHAPES[Number(m.type)];
    if (!shape) {
      skipped++;
      continue;
    }
    const p = m.pose?.position ?? {};
    const q = m.pose?.orientation ?? {};
    const s = m.scale ?? {};
    const c = m.color ?? {};
    const n = (/** @type {any} */ v, /** @type {number} */ d) => (Number.isFinite(Number(v)) ? Number(v) : d);
    const quat = [n(q.x, 0), n(q.y, 0), n(q.z, 0), n(q.w, 1)];
    if (!quat.some((v) => v !== 0)) quat[3] = 1; // an all-zero quaternion (common in hand-made markers) means none
    shapes.set(key, {
      key, shape, frame: frameId(m.header?.frame_id),
      position: [n(p.x, 0), n(p.y, 0), n(p.z, 0)],
      quaternion: quat,
      scale: [n(s.x, 0.01), n(s.y, 0.01), n(s.z, 0.01)],
      color: [n(c.r, 0.6), n(c.g, 0.6), n(c.b, 0.6), n(c.a, 1) || 1],
    });
  }
  return { skipped };
}

/**
 * The shapes as the view draws them, in its fixed frame: without one (no TF) as given; with one, each shape in another
 * frame moved to where TF puts that frame, and those in a frame TF does not link to the fixed one left out (as RViz
 * does), counted by frame.
 * @param {Iterable<Shape>} shapes @param {string | null} fixed @param {TfTree} tree
 * @returns {{ shapes: Shape[], unplaced: Record<string, number> }}
 */
export function placeShapes(shapes, fixed, tree) {
  /** @type {Shape[]} */
  const out = [];
  /** @type {Record<string, number>} */
  const unplaced = {};
  for (const s of shapes) {
    if (!fixed || !s.frame || s.frame === frameId(fixed)) {
      out.push(s);
      continue;
    }
    const at = tree.lookup(fixed, s.frame);
    if (!at) {
      unplaced[s.frame] = (unplaced[s.frame] ?? 0) + 1;
      continue;
    }
    const pose = compose(at, { p: s.position, q: s.quaternion });
    out.push({ ...s, position: pose.p, quaternion: pose.q });
  }
  return { shapes: out, unplaced };
}

/**
 * Where an arm's base stands in the view: from TF when it names a base frame (null until TF links it to the fixed
 * frame), else its base from the cell file.
 * @param {SceneArm} arm @param {string | null} fixed @param {TfTree} tree
 * @returns {import('./tf.js').Pose | null}
 */
export function armBase(arm, fixed, tree) {
  if (fixed && arm.base_frame) return tree.lookup(fixed, arm.base_frame);
  return baseToPose(arm.base);
}

/** Named camera views. */
export const PRESETS = /** @type {const} */ (['front', 'top', 'side']);

/**
 * Where the camera goes for a named view of a scene whose content fits a sphere (centre, radius).
 * Front looks along +x (from -x, a little from the right and from above, as one stands at a cell), side along
 * -y (from +y), top straight down (a hair off vertical, so the orbit keeps its up).
 * @param {'front' | 'top' | 'side'} name
 * @param {number[]} center
 * @param {number} radius
 * @param {number} fovDeg  the camera's vertical field of view
 * @param {number} aspect  width / height
 * @returns {{ position: number[], target: number[] }}
 */
export function presetPose(name, center, radius, fovDeg, aspect) {
  const r = Math.max(radius, 0.2);
  // Far enough that the sphere fits the narrower of the two fields of view.
  const vfov = (fovDeg * Math.PI) / 180;
  const hfov = 2 * Math.atan(Math.tan(vfov / 2) * Math.max(aspect, 0.1));
  const d = (r / Math.sin(Math.min(vfov, hfov) / 2)) * 1.05;
  const [cx, cy, cz] = center;
  /** @type {Record<string, number[]>} */
  const dir = { front: [-1, -0.3, 0.6], side: [0, 1, 0.5], top: [-0.001, 0, 1] };
  const v = dir[name] ?? dir.front;
  const len = Math.hypot(v[0], v[1], v[2]);
  return { position: [cx + (v[0] / len) * d, cy + (v[1] / len) * d, cz + (v[2] / len) * d], target: [cx, cy, cz] };
}

/** @param {number} v rad @returns {string} */
export const formatJoint = (v) => `${fmtFixed(v, 3)} rad (${fmtFixed((v * 180) / Math.PI, 1)}°)`;

/**
 * A routine's recorded TCP poses as a path to draw: the positions (base frame of its group's arm) of its pose steps.
 * @param {{ name: string, group: string, steps: { kind: string, pose: number[] }[] }} routine
 * @returns {{ name: string, group: string, points: number[][] }}
 */
export function routinePath(routine) {
  const points = routine.steps
    .filter((s) => s.kind === 'pose' && s.pose.length >= 3 && s.pose.slice(0, 3).every(Number.isFinite))
    .map((s) => s.pose.slice(0, 3));
  return { name: routine.name, group: routine.group, points };
}

/** What a frame of the 3D view may cost (ms of the page's own time) before it draws at the lower rate. */
export const FRAME_COST_MS = 8;

/**
 * How many frames a second the 3D view draws at most. A touch device (a phone, a tablet) keeps to 30, so a moving
 * arm leaves its page time for the controls; a desktop draws up to 60 (each joint state that comes, 50 a second),
 * unless its frames cost more than FRAME_COST_MS each (a software renderer, a slow machine), then 30 as well.
 * @param {{ coarse: boolean, frameMs: number }} o  coarse: the primary pointer is a finger; frameMs: a frame's
 *   mean cost so far
 * @returns {30 | 60}
 */
export function frameCap({ coarse, frameMs }) {
  return coarse || frameMs > FRAME_COST_MS ? 30 : 60;
}
