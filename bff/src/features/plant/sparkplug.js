// Sparkplug B (spBv1.0) for one edge node: topics, the metric set a cell reports, and the payloads of its birth,
// data and death. Payloads are encoded and decoded by Eclipse Tahu's `sparkplug-payload`; this file decides only
// what goes in them, so it is tested without a broker.
import sparkplug from 'sparkplug-payload';

const codec = sparkplug.get('spBv1.0');
export const NAMESPACE = 'spBv1.0';
export const REBIRTH = 'Node Control/Rebirth';

/** @typedef {'NBIRTH'|'NDEATH'|'NDATA'|'NCMD'|'DBIRTH'|'DDEATH'|'DDATA'|'DCMD'} MessageType */
/** @typedef {'String'|'Boolean'|'UInt32'|'Int8'|'Double'|'UInt64'} MetricType */
/** @typedef {{name: string, type: MetricType}} MetricDef */
/** @typedef {string | number | boolean | null} MetricValue */

/** @param {string} group @param {MessageType} type @param {string} node */
export const topicOf = (group, type, node) => `${NAMESPACE}/${group}/${type}/${node}`;

/**
 * An edge node's (or device's) topic, or null for anything else (STATE, another namespace, a malformed name).
 * @param {string} topic @returns {{group: string, type: MessageType, node: string, device: string | null} | null}
 */
export function parseTopic(topic) {
  const p = topic.split('/');
  if (p[0] !== NAMESPACE || p.length < 4 || p.length > 5 || p.some((x) => x === '')) return null;
  if (!/^[ND](BIRTH|DEATH|DATA|CMD)$/.test(p[2])) return null;
  return { group: p[1], type: /** @type {MessageType} */ (p[2]), node: p[3], device: p[4] ?? null };
}

/**
 * The metrics a cell reports, from its cell file: one per motion group and module, so a plant's SCADA sees the
 * same names on every cell of the same shape.
 * @param {{groups: string[], modules: string[]}} shape
 * @returns {MetricDef[]}
 */
export function cellMetrics({ groups, modules }) {
  /** @type {MetricDef[]} */
  const m = [
    { name: 'Properties/Name', type: 'String' },
    { name: 'Properties/URL', type: 'String' },
    { name: 'ROS/Connected', type: 'Boolean' },
    { name: 'Mode', type: 'String' },
    { name: 'Safety/Status', type: 'String' },
    { name: 'Alarms/Active', type: 'UInt32' },
    { name: 'Alarms/Most severe', type: 'String' },
    { name: 'Alarms/Highest severity', type: 'Int8' },
    { name: 'Process/State', type: 'String' },
    { name: 'Process/Operation', type: 'String' },
    { name: 'Process/Cycles done', type: 'UInt32' },
    { name: 'Process/Last cycle time', type: 'Double' },
  ];
  for (const g of groups) m.push({ name: `Robot/${g}/Connected`, type: 'Boolean' }, { name: `Robot/${g}/Mode`, type: 'String' });
  for (const x of modules) m.push({ name: `Modules/${x}`, type: 'String' });
  return m;
}

/** @param {MetricDef} d @param {MetricValue} value @param {number} timestamp */
function metric(d, value, timestamp) {
  return value === null || value === undefined
    ? { name: d.name, type: d.type, value: null, isNull: true, timestamp }
    : { name: d.name, type: d.type, value, timestamp };
}

/**
 * The edge node's Sparkplug session: bdSeq per MQTT connection, seq per message (0..255, NBIRTH is 0), and what
 * was last reported, so NDATA carries only what changed (report by exception).
 */
export class EdgeSession {
  /** @param {MetricDef[]} defs @param {number} [bdSeq] the first connection's (0..255) */
  constructor(defs, bdSeq = 0) {
    this.defs = defs;
    this.byName = new Map(defs.map((d) => [d.name, d]));
    this.bdSeq = bdSeq;
    this.seq = 0;
    /** @type {Map<string, MetricValue>} */
    this.sent = new Map();
  }

  /** The will for the next connection (NDEATH with its bdSeq): call before each CONNECT. @param {number} now */
  death(now) {
    return codec.encodePayload({ timestamp: now, metrics: [{ name: 'bdSeq', type: 'UInt64', value: this.bdSeq }] });
  }

  /** A connection ended: the next one has the next bdSeq (0..255). */
  nextConnection() {
    this.bdSeq = (this.bdSeq + 1) % 256;
  }

  /** NBIRTH: every metric with its current value, seq 0. @param {Record<string, MetricValue>} values @param {number} now */
  birth(values, now) {
    this.seq = 0;
    this.sent = new Map(this.defs.map((d) => [d.name, values[d.name] ?? null]));
    return codec.encodePayload({
      timestamp: now, seq: 0,
      metrics: [
        { name: 'bdSeq', type: 'UInt64', value: this.bdSeq, timestamp: now },
        { name: REBIRTH, type: 'Boolean', value: false, timestamp: now },
        ...this.defs.map((d) => metric(d, values[d.name] ?? null, now)),
      ],
    });
  }

  /**
   * NDATA with the metrics that changed since they were last reported, or null when none did.
   * @param {Record<string, MetricValue>} values @param {number} now
   */
  data(values, now) {
    const changed = this.defs.filter((d) => !sameValue(this.sent.get(d.name) ?? null, values[d.name] ?? null));
    if (!changed.length) return null;
    for (const d of changed) this.sent.set(d.name, values[d.name] ?? null);
    this.seq = (this.seq + 1) % 256;
    return codec.encodePayload({ timestamp: now, seq: this.seq, metrics: changed.map((d) => metric(d, values[d.name] ?? null, now)) });
  }
}

/** @param {MetricValue} a @param {MetricValue} b */
const sameValue = (a, b) => a === b || (typeof a === 'number' && typeof b === 'number' && Number.isNaN(a) && Number.isNaN(b));

/** A NCMD asks for a rebirth: its Node Control/Rebirth metric is true. @param {Uint8Array} payload */
export function asksRebirth(payload) {
  const p = decode(payload);
  return Boolean(p?.metrics?.some((m) => m.name === REBIRTH && m.value === true));
}

/** The NCMD a host sends to ask a node for its birth. @param {number} now */
export const rebirthCommand = (now) => codec.encodePayload({ timestamp: now, metrics: [{ name: REBIRTH, type: 'Boolean', value: true }] });

/**
 * A payload as plain values (64-bit integers as numbers), or null when it is not a Sparkplug B payload.
 * @param {Uint8Array} payload
 * @returns {{timestamp: number | null, seq: number | null, metrics: {name: string, type: string, value: MetricValue}[]} | null}
 */
export function decode(payload) {
  let p;
  try {
    p = codec.decodePayload(payload);
  } catch {
    return null;
  }
  const num = (/** @type {any} */ v) => (v === null || v === undefined ? null : Number(v));
  return {
    timestamp: num(p.timestamp),
    seq: num(p.seq),
    metrics: (p.metrics || []).map((m) => ({
      name: String(m.name ?? ''), type: String(m.type ?? ''),
      value: m.isNull || m.value === undefined || m.value === null ? null
        : typeof m.value === 'object' && 'low' in m.value ? Number(m.value) : /** @type {MetricValue} */ (m.value),
    })),
  };
}

export { codec };
