// What the /ros relay owes one browser, and how much of it may be on the wire. Pure: no sockets, no timers.
//
// ClientOutbox: topic messages (`op: publish`) wait in one lane per topic and encoding, bounded by the
// subscription's `queue_length` (a newer message pushes out the oldest unsent one: latest wins); every
// other frame (service responses, status, fragments, png, action results...) waits in the reply queue,
// which is never dropped from but is bounded in bytes: past the bound the owner must disconnect the client.
// Frames leave in arrival order (the oldest head among the reply queue and the lanes goes first).
//
// SendWindow: bytes written to the socket that the browser has not yet confirmed reading. A WebSocket ping
// follows the written bytes; its pong proves everything before it was read, kernel buffers included
// (Node cannot shrink a TCP socket's SO_SNDBUF, which Linux auto-tunes up to megabytes).
import { decode as cborDecode } from 'cbor-x';

/** @typedef {{data: Buffer, binary: boolean, seq: number, lane?: string}} OutFrame */

/** the send window's delivery rate is the best sample of this long (ms), at most this many samples */
const RATE_SPAN_MS = 10_000;
const RATE_SAMPLES = 64;

export const DEFAULTS = Object.freeze({
  /** lane bound when a subscription gives no queue_length (or 0, roslib's default): the newest message only */
  defaultQueueLength: 1,
  /** the largest queue_length honoured (a lane of 30 KB images then holds at most ~3 MB) */
  maxQueueLength: 100,
  /** unsent non-droppable replies per client before it is disconnected */
  maxReplyBytes: 8 * 1024 * 1024,
  /** bytes written but not confirmed read (pong) before the relay stops writing to that client: the least
   * window; it grows to twice what the link delivers in its shortest round trip (SendWindow) */
  windowBytes: 48 * 1024,
  /** the most the send window grows to */
  maxWindowBytes: 4 * 1024 * 1024,
  /** a ping follows a write once this many bytes and pingEveryMs have passed since the last one, and always when
   * the window fills: on a fast link a ping per window, not per frame (each costs a write, a pong and a read) */
  pingEveryBytes: 12 * 1024,
  pingEveryMs: 100,
});

/**
 * `op` and `topic` of a rosbridge frame, read from its first bytes when the frame has rosbridge's usual
 * `{"op":..,"topic":..,"msg":..}` shape (JSON text or CBOR map); otherwise the frame is decoded.
 * @param {Buffer} data @param {boolean} isBinary @returns {{op?: string, topic?: string}}
 */
export function classify(data, isBinary) {
  if (isBinary) {
    const head = cborHead(data);
    if (head.op && (head.op !== 'publish' || head.topic)) return head;
    try {
      const m = cborDecode(data);
      return { op: typeof m?.op === 'string' ? m.op : undefined, topic: typeof m?.topic === 'string' ? m.topic : undefined };
    } catch { return {}; }
  }
  const head = data.subarray(0, 512).toString('latin1');
  const fast = /^\s*\{\s*"op"\s*:\s*"([A-Za-z_]+)"\s*(?:,\s*"topic"\s*:\s*"([^"\\]*)")?/.exec(head);
  if (fast && (fast[1] !== 'publish' || fast[2] !== undefined)) return { op: fast[1], topic: fast[2] };
  if (!head.includes('"publish"')) return fast ? { op: fast[1] } : {};
  try {
    const m = JSON.parse(data.toString('utf8'));
    return { op: typeof m?.op === 'string' ? m.op : undefined, topic: typeof m?.topic === 'string' ? m.topic : undefined };
  } catch { return {}; }
}

/** The leading text-string pairs of a CBOR map (stops at the first value that is not a short text string). @param {Buffer} b */
function cborHead(b) {
  /** @type {{op?: string, topic?: string}} */
  const out = {};
  let i = 0;
  const first = b[i++];
  if (first === undefined || first >> 5 !== 5) return out;
  let n = first & 31;
  if (n === 24) n = b[i++];
  else if (n > 24) n = 8; // larger or indefinite maps: read a few pairs at most
  /** @returns {string|undefined} */
  const text = () => {
    const h = b[i];
    if (h === undefined || h >> 5 !== 3) return undefined;
    let len = h & 31; i++;
    if (len === 24) len = b[i++];
    else if (len === 25) { len = b.readUInt16BE(i); i += 2; } else if (len > 25) return undefined;
    if (len === undefined || i + len > b.length) return undefined;
    const s = b.toString('utf8', i, i + len); i += len;
    return s;
  };
  for (let k = 0; k < Math.min(n, 8); k++) {
    const key = text(); if (key === undefined) break;
    const val = text(); if (val === undefined) break;
    if (key === 'op') out.op = val;
    else if (key === 'topic') out.topic = val;
  }
  return out;
}

export class ClientOutbox {
  /** @param {Partial<typeof DEFAULTS>} [o] */
  constructor(o = {}) {
    const c = { ...DEFAULTS, ...o };
    this.defaultQueueLength = c.defaultQueueLength;
    this.maxQueueLength = c.maxQueueLength;
    this.maxReplyBytes = c.maxReplyBytes;
    /** topic -> (subscription id -> queue_length asked) */
    this.subs = new Map();
    /** @type {Map<string, OutFrame[]>} lane key (encoding + topic) -> unsent messages, oldest first */
    this.lanes = new Map();
    /** @type {OutFrame[]} */
    this.replies = [];
    this.replyHead = 0;
    this.seq = 0;
    // Counters (tests, logs, benchmarks).
    this.queuedBytes = 0;
    this.replyBytes = 0;
    this.dropped = 0;
    this.droppedBytes = 0;
    this.peakQueuedBytes = 0;
  }

  /** A request the browser sent on (after the guard): subscriptions set the lane bounds. @param {any} msg */
  noteRequest(msg) {
    if (!msg || typeof msg.topic !== 'string') return;
    if (msg.op === 'subscribe') {
      let m = this.subs.get(msg.topic);
      if (!m) this.subs.set(msg.topic, (m = new Map()));
      const q = Number.isInteger(msg.queue_length) && msg.queue_length > 0 ? msg.queue_length : this.defaultQueueLength;
      m.set(typeof msg.id === 'string' ? msg.id : '', Math.min(q, this.maxQueueLength));
    } else if (msg.op === 'unsubscribe') {
      const m = this.subs.get(msg.topic);
      if (m && typeof msg.id === 'string' && m.size > 1) m.delete(msg.id);
      else this.subs.delete(msg.topic);
    }
  }

  /** Lane bound of a topic: the largest queue_length among its subscriptions (rosbridge merges them so). @param {string} topic */
  queueLengthOf(topic) {
    const m = this.subs.get(topic);
    return m && m.size ? Math.max(...m.values()) : this.defaultQueueLength;
  }

  /**
   * Queue a frame from rosbridge.
   * @param {Buffer} data @param {boolean} binary @param {{op?: string, topic?: string}} [kind] (classify(data, binary) if omitted)
   * @returns {boolean} false when the reply queue is past its bound (the caller disconnects the client)
   */
  push(data, binary, kind = classify(data, binary)) {
    /** @type {OutFrame} */
    const f = { data, binary, seq: this.seq++ };
    this.queuedBytes += data.length;
    if (kind.op === 'publish' && kind.topic !== undefined) {
      f.lane = (binary ? 'b' : 't') + kind.topic;
      let lane = this.lanes.get(f.lane);
      if (!lane) this.lanes.set(f.lane, (lane = []));
      lane.push(f);
      const bound = this.queueLengthOf(kind.topic);
      while (lane.length > bound) {
        const old = /** @type {OutFrame} */ (lane.shift());
        this.queuedBytes -= old.data.length;
        this.dropped++;
        this.droppedBytes += old.data.length;
      }
    } else {
      this.replies.push(f);
      this.replyBytes += data.length;
    }
    if (this.queuedBytes > this.peakQueuedBytes) this.peakQueuedBytes = this.queuedBytes;
    return this.replyBytes <= this.maxReplyBytes;
  }

  get length() {
    let n = this.replies.length - this.replyHead;
    for (const lane of this.lanes.values()) n += lane.length;
    return n;
  }

  /** The oldest unsent frame, removed from the outbox. @returns {OutFrame|undefined} */
  shift() {
    /** @type {OutFrame|undefined} */
    let best = this.replies[this.replyHead];
    /** @type {OutFrame[]|undefined} */
    let from;
    for (const lane of this.lanes.values()) if (lane.length && (!best || lane[0].seq < best.seq)) { best = lane[0]; from = lane; }
    if (!best) return undefined;
    if (from) {
      from.shift();
      if (!from.length) this.lanes.delete(/** @type {string} */ (best.lane));
    } else {
      /** @type {any} */ (this.replies)[this.replyHead++] = undefined;
      this.replyBytes -= best.data.length;
      if (this.replyHead > 64 && this.replyHead * 2 > this.replies.length) { this.replies = this.replies.slice(this.replyHead); this.replyHead = 0; }
    }
    this.queuedBytes -= best.data.length;
    return best;
  }
}

/**
 * How many bytes may be written to one browser before it confirms reading them (a WebSocket ping after the
 * bytes, its pong back). A fixed window allows one window per round trip: 48 KiB over an 80 ms link is 600 KB/s,
 * fewer than 30 frames of 30 KB a second. So the window follows the link, as BBR sizes its congestion window:
 * twice the delivery rate (the best sample of the last 10 s) times the round trip (the least seen on this
 * connection: a probe() when it opens, before any frame is in flight), never below `windowBytes` nor above
 * `maxWindowBytes`. On a slow link that round trip is the link's own, without our frames queued in it, so the
 * window stays at `windowBytes` there (a larger one would only queue older frames); on a long fast link it
 * grows until the stream's own rate is delivered.
 */
export class SendWindow {
  /**
   * @param {Partial<Pick<typeof DEFAULTS, 'windowBytes'|'pingEveryBytes'|'pingEveryMs'|'maxWindowBytes'>>} [o]
   * @param {() => number} [now] ms
   */
  constructor(o = {}, now = () => performance.now()) {
    this.minWindowBytes = o.windowBytes ?? DEFAULTS.windowBytes;
    this.maxWindowBytes = Math.max(this.minWindowBytes, o.maxWindowBytes ?? DEFAULTS.maxWindowBytes);
    this.windowBytes = this.minWindowBytes;
    this.pingEveryBytes = o.pingEveryBytes ?? DEFAULTS.pingEveryBytes;
    this.pingEveryMs = o.pingEveryMs ?? DEFAULTS.pingEveryMs;
    this.pingedAtMs = -Infinity;
    this.ackedAtMs = now();
    this.now = now;
    this.sentBytes = 0;
    this.ackedBytes = 0;
    this.pingedAt = 0;
    this.pingSeq = 0;
    /** @type {Map<string, {bytes: number, at: number, acked: number, ackedAt: number}>} ping payload -> sentBytes, time, ackedBytes and its time when it was written */
    this.pings = new Map();
    /** @type {{at: number, rate: number}[]} delivery rate samples (bytes/ms) of the last RATE_SPAN_MS */
    this.rates = [];
    this.minRttMs = Infinity;
    this.rate = 0;
  }

  /** Bytes written and not yet confirmed read. */
  get unacked() { return this.sentBytes - this.ackedBytes; }

  /** May another frame be written now? (One frame may overshoot the window, so any frame size gets through.) */
  open() { return this.unacked < this.windowBytes; }

  /**
   * Account for a written frame. @param {number} bytes
   * @returns {string|null} the payload of a ping to write right after it, or null
   */
  wrote(bytes) {
    this.sentBytes += bytes;
    const t = this.now();
    if (this.open() && (this.sentBytes - this.pingedAt < this.pingEveryBytes || t - this.pingedAtMs < this.pingEveryMs)) return null;
    this.pingedAt = this.sentBytes;
    this.pingedAtMs = t;
    const payload = `bp${++this.pingSeq}`;
    this.pings.set(payload, { bytes: this.sentBytes, at: t, acked: this.ackedBytes, ackedAt: this.ackedAtMs });
    // Only a bounded number of pings is ever outstanding: each one needs pingEveryBytes or a full window.
    return payload;
  }

  /**
   * A ping to write now, before anything is in flight (the socket just opened): its round trip is the link's own,
   * not our frames' queue. @returns {string} its payload
   */
  probe() {
    const payload = `bp${++this.pingSeq}`;
    this.pings.set(payload, { bytes: this.sentBytes, at: this.now(), acked: this.ackedBytes, ackedAt: this.ackedAtMs });
    return payload;
  }

  /** A pong arrived. @param {string} payload @returns {boolean} whether it was one of ours */
  pong(payload) {
    const ping = this.pings.get(payload);
    if (ping === undefined) return false;
    for (const [k, v] of this.pings) { if (v.bytes > ping.bytes) break; this.pings.delete(k); }
    const t = this.now();
    const rtt = Math.max(0.1, t - ping.at);
    // What was unconfirmed when the ping went out has been read since the confirmation before it (as BBR samples
    // its delivery rate). Pings are sparse on a fast link: bytes written long before this ping were not all read
    // within its round trip.
    const rate = (ping.bytes - ping.acked) / Math.max(rtt, t - ping.ackedAt);
    if (ping.bytes > this.ackedBytes) this.ackedBytes = ping.bytes;
    this.ackedAtMs = t;
    this.minRttMs = Math.min(this.minRttMs, rtt);
    this.rates.push({ at: t, rate });
    while (this.rates.length > RATE_SAMPLES || this.rates[0].at < t - RATE_SPAN_MS) this.rates.shift();
    this.rate = Math.max(...this.rates.map((x) => x.rate));
    this.windowBytes = Math.round(Math.min(this.maxWindowBytes, Math.max(this.minWindowBytes, 2 * this.rate * this.minRttMs)));
    return true;
  }
}
