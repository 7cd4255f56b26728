// The recordings directory as the Recordings page sees it: the MCAP files the recorder node wrote, each described
// by the JSON file beside it (why, when, topics, timeline: cell_nodes/recorder/sidecar.py). A recording without a
// readable description is still listed, by its name, size and time. No MCAP parsing here.
import fsp from 'node:fs/promises';
import path from 'node:path';

/** A recording's file name: no path, no hidden or temp file (".tmp-..."), .mcap. */
export const RECORDING_NAME = { type: 'string', pattern: '^[A-Za-z0-9][A-Za-z0-9._-]{0,200}\\.mcap$', maxLength: 206 };
const NAME_RE = new RegExp(RECORDING_NAME.pattern);
const LANE_IDS = ['alarms', 'process', 'mode'];

/**
 * @typedef {{name: string, at_ms: number, reason: string, size: number, duration_s: number, messages: number,
 *   alarms: string[]}} Recording
 * @typedef {{t_ms: number, text: string}} Change
 * @typedef {{id: string, title: string, changes: Change[]}} Lane
 * @typedef {Recording & {start_ms: number, end_ms: number, topics: {topic: string, type: string, count: number}[],
 *   timeline: {lanes: Lane[]}}} RecordingDetail
 */

/** A client error: its status and message, and the same as a stable code and params for the app (`recorder.not_found` {name}). */
export class RecordingError extends Error {
  /** @param {number} status @param {string} message @param {string} [code] @param {Record<string, string | number>} [params] */
  constructor(status, message, code = undefined, params = undefined) {
    super(message);
    this.status = status;
    this.code = code;
    this.params = params;
  }
}

/** @param {string} name */
const notFound = (name) => new RecordingError(404, `no recording ${name}`, 'recorder.not_found', { name });

/** @param {any} s @param {import('../../core/config/env.js').Env} env */
export const recordingsDir = (s, env) => (typeof s?.directory === 'string' ? path.resolve(s.directory) : path.join(env.dataDir, 'recordings'));

const num = (v, fallback) => (typeof v === 'number' && Number.isFinite(v) ? v : fallback);
const str = (v) => (typeof v === 'string' ? v : '');

export class Recordings {
  /** @param {{dir: string}} o */
  constructor({ dir }) {
    this.dir = dir;
  }

  /** @param {string} name @returns {string} the file's path; 400 for a name that is not a recording's */
  pathOf(name) {
    if (!NAME_RE.test(name)) throw new RecordingError(400, `not a recording's name: ${JSON.stringify(name.slice(0, 80))}`, 'recorder.invalid_name', { name: name.slice(0, 80) });
    return path.join(this.dir, name);
  }

  /** @param {string} name */
  sidecarOf(name) {
    return path.join(this.dir, `${name.slice(0, -'.mcap'.length)}.json`);
  }

  /** Newest first. @returns {Promise<Recording[]>} */
  async list() {
    let names;
    try {
      names = (await fsp.readdir(this.dir, { withFileTypes: true })).filter((e) => e.isFile() && NAME_RE.test(e.name)).map((e) => e.name);
    } catch (e) {
      if (/** @type {any} */ (e).code === 'ENOENT') return [];
      throw e;
    }
    const out = (await Promise.all(names.map((n) => this.describe(n).catch(() => null)))).filter((r) => r !== null);
    return out.map(summary).sort((a, b) => b.at_ms - a.at_ms || (a.name < b.name ? 1 : -1));
  }

  /** @param {string} name @returns {Promise<RecordingDetail>} 404 when there is no such recording */
  async describe(name) {
    const file = this.pathOf(name);
    let st;
    try {
      st = await fsp.stat(file);
    } catch (e) {
      if (/** @type {any} */ (e).code === 'ENOENT') throw notFound(name);
      throw e;
    }
    if (!st.isFile()) throw notFound(name);
    /** @type {any} */
    let d = null;
    try {
      d = JSON.parse(await fsp.readFile(this.sidecarOf(name), 'utf8'));
    } catch {
      d = null; // missing or torn: listed by what the file system says
    }
    if (!d || typeof d !== 'object' || Array.isArray(d)) d = {};
    const at = num(d.at_ms, st.mtimeMs);
    const lanes = Array.isArray(d.timeline?.lanes) ? d.timeline.lanes : [];
    return {
      name, at_ms: at, reason: str(d.reason), size: st.size, duration_s: num(d.duration_s, 0), messages: num(d.messages, 0),
      alarms: Array.isArray(d.alarms) ? d.alarms.filter((a) => typeof a === 'string') : [],
      start_ms: num(d.start_ms, at), end_ms: num(d.end_ms, at),
      topics: (Array.isArray(d.topics) ? d.topics : []).filter((t) => typeof t?.topic === 'string')
        .map((t) => ({ topic: t.topic, type: str(t.type), count: num(t.count, 0) })),
      timeline: {
        lanes: lanes.filter((l) => LANE_IDS.includes(l?.id)).map((l) => ({
          id: l.id, title: str(l.title) || l.id,
          changes: (Array.isArray(l.changes) ? l.changes : []).filter((c) => typeof c?.t_ms === 'number' && typeof c?.text === 'string')
            .map((c) => ({ t_ms: c.t_ms, text: c.text })),
        })),
      },
    };
  }

  /** A readable stream of the file and its size, for a download. @param {string} name */
  async open(name) {
    const file = this.pathOf(name);
    const handle = await fsp.open(file, 'r').catch((e) => {
      throw e.code === 'ENOENT' ? notFound(name) : e;
    });
    const st = await handle.stat();
    if (!st.isFile()) {
      await handle.close();
      throw notFound(name);
    }
    return { size: st.size, stream: handle.createReadStream() };
  }

  /** Delete a recording and its description. @param {string} name */
  async remove(name) {
    const file = this.pathOf(name);
    try {
      await fsp.unlink(file);
    } catch (e) {
      if (/** @type {any} */ (e).code === 'ENOENT') throw notFound(name);
      throw e;
    }
    await fsp.unlink(this.sidecarOf(name)).catch(() => {});
  }
}

/** @param {RecordingDetail} d @returns {Recording} */
function summary(d) {
  const { name, at_ms, reason, size, duration_s, messages, alarms } = d;
  return { name, at_ms, reason, size, duration_s, messages, alarms };
}
