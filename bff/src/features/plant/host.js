// The plant page's side: a Sparkplug host application that follows every edge node of the plant's groups from
// their births, data and deaths. It only reads; the one thing it sends is a rebirth request (NCMD) to a node whose
// messages it cannot place (one heard before its birth, or a gap in its seq), as the specification asks.
import { topicOf, parseTopic, decode, rebirthCommand } from './sparkplug.js';
import { ShiftStats } from './shift.js';

/**
 * @typedef {object} PlantCell one edge node as the plant page shows it
 * @property {string} id @property {string} group @property {string} node @property {string} name @property {string} url
 * @property {boolean} online @property {number} since @property {boolean} ros
 * @property {string} mode @property {string} safety @property {number} alarms @property {string} alarm @property {number} severity
 * @property {string} process @property {string} operation @property {number} cycles @property {number} last_cycle_s
 * @property {{group: string, connected: boolean, mode: string}[]} robots
 * @property {{name: string, state: string}[]} modules
 * @property {number} updated
 * @property {{cycles_last_hour: number, running_share: number | null, observed_s: number}} shift cycles in the last
 *   hour, and the share of the shift (8 h, or since the view first heard of the cell) spent running
 */

/** @param {Map<string, any>} m @returns {Omit<PlantCell, 'id'|'group'|'node'|'online'|'since'|'updated'|'shift'>} */
export function cellView(m) {
  const s = (/** @type {string} */ k) => (typeof m.get(k) === 'string' ? m.get(k) : '');
  const n = (/** @type {string} */ k, d = 0) => (typeof m.get(k) === 'number' ? m.get(k) : d);
  const robots = new Map();
  /** @type {{name: string, state: string}[]} */
  const modules = [];
  for (const [k, v] of m) {
    const r = /^Robot\/(.+)\/(Connected|Mode)$/.exec(k);
    if (r) {
      const x = robots.get(r[1]) ?? { group: r[1], connected: false, mode: '' };
      if (r[2] === 'Connected') x.connected = v === true;
      else x.mode = typeof v === 'string' ? v : '';
      robots.set(r[1], x);
    }
    const mod = /^Modules\/(.+)$/.exec(k);
    if (mod) modules.push({ name: mod[1], state: typeof v === 'string' ? v : '' });
  }
  return {
    name: s('Properties/Name'), url: s('Properties/URL'), ros: m.get('ROS/Connected') === true,
    mode: s('Mode'), safety: s('Safety/Status'), alarms: n('Alarms/Active'), alarm: s('Alarms/Most severe'),
    severity: n('Alarms/Highest severity', -1), process: s('Process/State'), operation: s('Process/Operation'),
    cycles: n('Process/Cycles done'), last_cycle_s: n('Process/Last cycle time'), robots: [...robots.values()], modules,
  };
}

export class PlantHost {
  /**
   * @param {object} o
   * @param {string[]} o.groups
   * @param {(topic: string, payload: Uint8Array) => void} o.send publish (the rebirth request)
   * @param {() => void} [o.onChange]
   * @param {(m: string) => void} [o.log]
   * @param {() => number} [o.now]
   */
  constructor({ groups, send, onChange = () => {}, log = () => {}, now = Date.now }) {
    this.groups = groups;
    this.send = send;
    this.onChange = onChange;
    this.log = log;
    this.now = now;
    /** @type {Map<string, {group: string, node: string, metrics: Map<string, any>, online: boolean, since: number, seq: number, bdSeq: number | null, updated: number, born: boolean}>} */
    this.nodes = new Map();
    /** @type {Map<string, ShiftStats>} */
    this.shifts = new Map();
    /** @type {Map<string, number>} when each node was last asked for a rebirth */
    this.asked = new Map();
  }

  /** What to subscribe: every edge node message of the groups. */
  subscriptions() {
    return this.groups.flatMap((g) => ['NBIRTH', 'NDATA', 'NDEATH'].map((t) => `spBv1.0/${g}/${t}/+`));
  }

  /** @param {string} topic @param {Uint8Array} payload */
  onMessage(topic, payload) {
    const t = parseTopic(topic);
    if (!t || t.device !== null || !this.groups.includes(t.group)) return;
    const p = decode(payload);
    const id = `${t.group}/${t.node}`;
    if (!p) {
      this.log(`plant view: ignored a message on ${topic} that is not a Sparkplug B payload (${payload.length} bytes)`);
      return;
    }
    const now = this.now();
    const n = this.nodes.get(id);
    if (t.type === 'NBIRTH') {
      const bd = p.metrics.find((m) => m.name === 'bdSeq')?.value;
      const metrics = new Map(p.metrics.filter((m) => m.name !== 'bdSeq' && !m.name.startsWith('Node Control/')).map((m) => [m.name, m.value]));
      this.nodes.set(id, {
        group: t.group, node: t.node, metrics, online: true, since: n?.online ? n.since : now, seq: p.seq ?? 0,
        bdSeq: typeof bd === 'number' ? bd : null, updated: now, born: true,
      });
      this.observe(id);
      this.onChange();
    } else if (t.type === 'NDATA') {
      if (!n?.born || !n.online) return this.rebirth(t.group, t.node, 'data before its birth');
      const expected = (n.seq + 1) % 256;
      n.seq = p.seq ?? expected;
      n.updated = now;
      for (const m of p.metrics) n.metrics.set(m.name, m.value);
      this.observe(id);
      this.onChange();
      if (p.seq !== null && p.seq !== expected) this.rebirth(t.group, t.node, `seq ${p.seq} after ${(expected + 255) % 256}`);
    } else if (t.type === 'NDEATH') {
      const bd = p.metrics.find((m) => m.name === 'bdSeq')?.value;
      // A will left by an older connection of a node that was born again since: not this session's death.
      if (!n || !n.online || (n.bdSeq !== null && typeof bd === 'number' && bd !== n.bdSeq)) return;
      n.online = false;
      n.since = now;
      n.updated = now;
      this.observe(id);
      this.onChange();
    }
  }

  /** @param {string} id */
  observe(id) {
    const n = this.nodes.get(id);
    if (!n) return;
    let s = this.shifts.get(id);
    if (!s) this.shifts.set(id, (s = new ShiftStats()));
    s.observe(this.now(), { online: n.online, mode: n.metrics.get('Mode'), cycles: n.metrics.get('Process/Cycles done') });
  }

  /** @param {string} group @param {string} node @param {string} why */
  rebirth(group, node, why) {
    const id = `${group}/${node}`;
    const now = this.now();
    if (now - (this.asked.get(id) ?? -Infinity) < 5000) return;
    this.asked.set(id, now);
    this.log(`plant view: asked ${id} for a rebirth (${why})`);
    this.send(topicOf(group, 'NCMD', node), rebirthCommand(now));
  }

  /** @returns {PlantCell[]} */
  cells() {
    return [...this.nodes.entries()].map(([id, n]) => ({
      id, group: n.group, node: n.node, online: n.online, since: n.since, updated: n.updated, ...cellView(n.metrics),
      shift: (this.shifts.get(id) ?? new ShiftStats()).stats(this.now()),
    }));
  }
}
