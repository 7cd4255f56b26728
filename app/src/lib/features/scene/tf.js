/**
 * TF for the 3D view without three.js: a tree of frames from tf2_msgs/TFMessage (/tf and /tf_static), and where a
 * frame stands in the fixed frame the view draws in. Poses are { p: [x, y, z], q: [x, y, z, w] }.
 */

export const TF_TYPE = 'tf2_msgs/TFMessage';
export const TF_TOPIC = '/tf';
export const TF_STATIC_TOPIC = '/tf_static';

/** @typedef {{ p: number[], q: number[] }} Pose */

/** @param {number[]} a @param {number[]} b quaternions x, y, z, w @returns {number[]} a * b */
export function qmul(a, b) {
  const [ax, ay, az, aw] = a;
  const [bx, by, bz, bw] = b;
  return [
    aw * bx + ax * bw + ay * bz - az * by,
    aw * by - ax * bz + ay * bw + az * bx,
    aw * bz + ax * by - ay * bx + az * bw,
    aw * bw - ax * bx - ay * by - az * bz,
  ];
}

/** @param {number[]} q a unit quaternion @param {number[]} v @returns {number[]} v turned by q */
export function rotate(q, v) {
  const r = qmul(qmul(q, [v[0], v[1], v[2], 0]), [-q[0], -q[1], -q[2], q[3]]);
  return [r[0], r[1], r[2]];
}

/** @param {Pose} a @param {Pose} b @returns {Pose} b expressed through a (a then b) */
export function compose(a, b) {
  const t = rotate(a.q, b.p);
  return { p: [a.p[0] + t[0], a.p[1] + t[1], a.p[2] + t[2]], q: qmul(a.q, b.q) };
}

/** @param {Pose} a @returns {Pose} */
export function invert(a) {
  const qi = [-a.q[0], -a.q[1], -a.q[2], a.q[3]];
  const t = rotate(qi, a.p);
  return { p: [-t[0], -t[1], -t[2]], q: qi };
}

/** The pose of a base given as [x, y, z (m), yaw (deg)] (the cell file's base). @param {number[]} base @returns {Pose} */
export function baseToPose(base) {
  const half = ((base[3] ?? 0) * Math.PI) / 360;
  return { p: [base[0] ?? 0, base[1] ?? 0, base[2] ?? 0], q: [0, 0, Math.sin(half), Math.cos(half)] };
}

/** The heading of a pose's rotation about z, in degrees. @param {number[]} q @returns {number} */
export function yawDeg(q) {
  const [x, y, z, w] = q;
  return (Math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)) * 180) / Math.PI;
}

/** tf2 frame ids have no leading slash; tf (1) ones often do. @param {any} id */
export const frameId = (id) => String(id ?? '').replace(/^\/+/, '');

const IDENTITY = Object.freeze({ p: [0, 0, 0], q: [0, 0, 0, 1] });

/**
 * The frames TF has told us of: each child's parent and its pose in the parent (the latest one: the view shows
 * the present, it does not interpolate in time).
 */
export class TfTree {
  constructor() {
    /** @type {Map<string, { parent: string, pose: Pose }>} */
    this.frames = new Map();
  }

  /**
   * Take the transforms of a tf2_msgs/TFMessage; those that are not numbers, or would make a loop, are skipped.
   * @param {any} msg @returns {number} how many changed a frame
   */
  apply(msg) {
    let changed = 0;
    for (const t of Array.isArray(msg?.transforms) ? msg.transforms : []) {
      const child = frameId(t?.child_frame_id);
      const parent = frameId(t?.header?.frame_id);
      const tr = t?.transform?.translation ?? {};
      const ro = t?.transform?.rotation ?? {};
      const p = [tr.x, tr.y, tr.z].map(Number);
      const q = [ro.x, ro.y, ro.z, ro.w].map(Number);
      const norm = Math.hypot(...q);
      if (!child || !parent || child === parent || ![...p, ...q].every(Number.isFinite) || norm < 1e-9) continue;
      if (this.#ancestors(parent).includes(child)) continue; // a loop: tf2 refuses it too
      const pose = { p, q: q.map((v) => v / norm) };
      const old = this.frames.get(child);
      if (old && old.parent === parent && [...old.pose.p, ...old.pose.q].every((v, i) => v === [...p, ...pose.q][i])) continue;
      this.frames.set(child, { parent, pose });
      changed++;
    }
    return changed;
  }

  /** @param {string} frame @returns {string[]} the frame and its ancestors, up to its root */
  #ancestors(frame) {
    const out = [frame];
    let f = this.frames.get(frame);
    while (f && out.length <= this.frames.size) {
      out.push(f.parent);
      f = this.frames.get(f.parent);
    }
    return out;
  }

  /** @param {string} frame @returns {Pose} the frame's pose in its root */
  #inRoot(frame) {
    /** @type {Pose} */
    let pose = IDENTITY;
    for (const f of this.#ancestors(frame)) {
      const link = this.frames.get(f);
      if (link) pose = compose(link.pose, pose);
    }
    return pose;
  }

  /**
   * Where `frame` stands in `fixed` (a point in `frame` maps to pose.p + pose.q * point), or null when TF does not
   * link the two.
   * @param {string} fixed @param {string} frame @returns {Pose | null}
   */
  lookup(fixed, frame) {
    const a = frameId(fixed);
    const b = frameId(frame);
    if (a === b) return { p: [0, 0, 0], q: [0, 0, 0, 1] };
    const ra = this.#ancestors(a);
    const rb = this.#ancestors(b);
    if (ra[ra.length - 1] !== rb[rb.length - 1]) return null;
    return compose(invert(this.#inRoot(a)), this.#inRoot(b));
  }
}
