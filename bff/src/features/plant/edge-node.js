// The cell as a Sparkplug B edge node: NBIRTH on every connection (after its NDEATH was left as the MQTT will),
// NDATA by exception at most every min_interval_ms, a rebirth when a host asks (NCMD Node Control/Rebirth), and an
// NDEATH on a clean shutdown. It never blocks the cell: publishing is fire-and-forget, QoS 0 for data (the next
// change or a rebirth supersedes a lost one) and QoS 1 for the death.
import { EdgeSession, topicOf, asksRebirth, NAMESPACE } from './sparkplug.js';
import { connectWithBackoff } from './mqtt-link.js';

export class EdgeNode {
  /**
   * @param {object} o
   * @param {string} o.url @param {import('mqtt').IClientOptions} o.options
   * @param {string} o.groupId @param {string} o.nodeId
   * @param {import('./sparkplug.js').MetricDef[]} o.defs
   * @param {() => Record<string, import('./sparkplug.js').MetricValue>} o.values
   * @param {number} [o.minIntervalMs] @param {number} [o.keepaliveS]
   * @param {(m: string) => void} [o.log]
   * @param {(s: import('./mqtt-link.js').LinkState) => void} [o.onState]
   * @param {typeof import('mqtt').connect} [o.connect]
   */
  constructor({ url, options, groupId, nodeId, defs, values, minIntervalMs = 200, keepaliveS = 10, log = () => {}, onState, connect }) {
    // A restarted BFF must not repeat its last bdSeq: the broker may publish the old process's will after the new
    // birth, and a host would take that death for the new session's. So a random start, and a client id of its own
    // (not per process): a new connection takes the old one's session over, and the broker publishes the old will
    // at once, before the new birth.
    this.session = new EdgeSession(defs, Math.floor(Math.random() * 256));
    this.values = values;
    this.minIntervalMs = minIntervalMs;
    this.topic = (/** @type {any} */ type) => topicOf(groupId, type, nodeId);
    this.lastSent = 0;
    /** @type {NodeJS.Timeout | null} */
    this.pending = null;
    this.born = false;
    const will = () => ({ topic: this.topic('NDEATH'), payload: Buffer.from(this.session.death(Date.now())), qos: /** @type {const} */ (1), retain: false });
    const { client, state } = connectWithBackoff({
      url, who: `plant edge node ${groupId}/${nodeId}`, log, onState, connect,
      options: { ...options, clean: true, keepalive: keepaliveS, clientId: `cell-${groupId}-${nodeId}`, will: will() },
    });
    this.client = client;
    this.state = state;
    client.on('connect', () => {
      client.subscribe([this.topic('NCMD'), `${NAMESPACE}/STATE/+`], { qos: 0 });
      this.birth();
    });
    client.on('close', () => {
      // The broker publishes this connection's NDEATH (or already did); the next CONNECT carries the next bdSeq.
      if (this.born) this.session.nextConnection();
      this.born = false;
      client.options.will = will();
    });
    client.on('message', (topic, payload, packet) => {
      if (topic === this.topic('NCMD') && asksRebirth(payload)) this.birth();
      else if (topic.startsWith(`${NAMESPACE}/STATE/`)) this.hostState(payload, packet.retain);
    });
  }

  /**
   * A host application came online (Sparkplug 3.0 STATE): it has not seen our birth, so send it again. A retained
   * STATE (delivered as we subscribe) is a host that was there before: our birth on connecting covers it.
   * @param {Buffer} payload @param {boolean} retained
   */
  hostState(payload, retained) {
    let s;
    try { s = JSON.parse(payload.toString()); } catch { return; }
    if (s?.online === true && !retained) this.birth();
  }

  birth() {
    if (!this.client.connected) return;
    this.clearPending();
    this.client.publish(this.topic('NBIRTH'), Buffer.from(this.session.birth(this.values(), Date.now())), { qos: 0 });
    this.born = true;
    this.lastSent = Date.now();
  }

  /** Something the report reads changed: send what changed now, or when the rate limit allows. */
  changed() {
    if (!this.born || this.pending) return;
    const wait = this.lastSent + this.minIntervalMs - Date.now();
    if (wait > 0) this.pending = setTimeout(() => { this.pending = null; this.flush(); }, wait);
    else this.flush();
  }

  flush() {
    if (!this.born || !this.client.connected) return;
    const p = this.session.data(this.values(), Date.now());
    if (!p) return;
    this.client.publish(this.topic('NDATA'), Buffer.from(p), { qos: 0 });
    this.lastSent = Date.now();
  }

  clearPending() {
    if (this.pending) clearTimeout(this.pending);
    this.pending = null;
  }

  /** A clean shutdown: say NDEATH ourselves (the broker does not send a will on a normal disconnect). */
  close() {
    this.clearPending();
    const c = this.client;
    if (c.connected && this.born) {
      c.publish(this.topic('NDEATH'), Buffer.from(this.session.death(Date.now())), { qos: 1 }, () => c.end(true));
      setTimeout(() => c.end(true), 500).unref();
    } else {
      c.end(true);
    }
  }
}
