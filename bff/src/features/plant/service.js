// The plant feature while the BFF runs: the cell's edge node (its state from its own rosbridge, reported on the
// plant's broker) and, when a role may see the plant page, the host that follows every cell of the plant.
import { CellReport } from './report.js';
import { RosReader } from './ros-reader.js';
import { EdgeNode } from './edge-node.js';
import { PlantHost } from './host.js';
import { brokerOptions, connectWithBackoff } from './mqtt-link.js';
import { NAMESPACE } from './sparkplug.js';

/** @typedef {import('./mqtt-link.js').LinkState} LinkState */

export class PlantService {
  /**
   * @param {object} o
   * @param {any} o.section the cell file's plant section
   * @param {any} o.cell
   * @param {import('../../core/config/env.js').Env} o.env
   * @param {boolean} o.view whether some role sees the plant page (then this BFF runs the host)
   * @param {(m: string) => void} o.log
   */
  constructor({ section, cell, env, view, log }) {
    const { url, options } = brokerOptions(section, env);
    const groupId = section.group_id;
    const nodeId = section.edge_node_id || cell.cell.id;
    /** @type {LinkState} */
    this.edgeLink = { state: 'off', since: Date.now(), error: '' };
    /** @type {LinkState} */
    this.viewLink = { state: 'off', since: Date.now(), error: '' };
    /** @type {Set<() => void>} */
    this.listeners = new Set();
    this.closers = /** @type {(() => void)[]} */ ([]);
    this.info = { broker: url, group_id: groupId, edge_node_id: nodeId };

    if (section.report !== false) {
      const report = new CellReport(cell, { url: env.plant.cellUrl || section.url || '' });
      const edge = new EdgeNode({
        url, options, groupId, nodeId, defs: report.defs, values: () => report.values(), log,
        minIntervalMs: section.min_interval_ms ?? 200, keepaliveS: section.keepalive_s ?? 10,
        onState: (s) => { this.edgeLink = s; },
      });
      const ros = new RosReader({
        url: `ws://127.0.0.1:${env.rosbridgePort}`, topics: report.shape.topics, log,
        onMessage: (topic, msg) => { report.onMessage(topic, msg); edge.changed(); },
        onLink: (up) => { report.setRos(up); edge.changed(); },
      });
      ros.start();
      this.closers.push(() => ros.close(), () => edge.close());
    }

    if (view) {
      const groups = section.groups ?? [groupId];
      /** @type {import('mqtt').MqttClient | null} */
      let client = null;
      this.host = new PlantHost({
        groups, log,
        send: (topic, payload) => client?.publish(topic, Buffer.from(payload), { qos: 0 }),
        onChange: () => this.emit(),
      });
      const host = this.host;
      // A host's STATE (Sparkplug 3.0): retained, its will says offline; edge nodes rebirth when a host comes online.
      const stateTopic = `${NAMESPACE}/STATE/plant-view-${nodeId}`;
      const c = connectWithBackoff({
        url, who: `plant view ${groups.join(', ')}`, log,
        onState: (s) => { this.viewLink = s; this.emit(); },
        options: {
          ...options, clean: true, keepalive: section.keepalive_s ?? 10, clientId: `plant-view-${nodeId}`,
          will: { topic: stateTopic, payload: Buffer.from(JSON.stringify({ online: false, timestamp: Date.now() })), qos: 1, retain: true },
        },
      });
      client = c.client;
      client.on('connect', () => {
        client?.subscribe(host.subscriptions(), { qos: 0 }, () => {
          client?.publish(stateTopic, JSON.stringify({ online: true, timestamp: Date.now() }), { qos: 1, retain: true });
        });
      });
      client.on('message', (topic, payload) => host.onMessage(topic, payload));
      // The shift's running share moves with time: the page gets it again twice a minute.
      const tick = setInterval(() => this.emit(), 30_000);
      tick.unref();
      this.closers.push(() => clearInterval(tick));
      this.closers.push(() => {
        const cl = /** @type {import('mqtt').MqttClient} */ (client);
        if (cl.connected) cl.publish(stateTopic, JSON.stringify({ online: false, timestamp: Date.now() }), { qos: 1, retain: true }, () => cl.end(true));
        else cl.end(true);
        setTimeout(() => cl.end(true), 500).unref();
      });
    }
  }

  /** What the plant page shows. */
  snapshot() {
    const link = this.viewLink;
    return { broker: { state: link.state, since: link.since, error: link.error }, cells: this.host ? this.host.cells() : [] };
  }

  /** The System page's line: this cell's link to the plant's broker. */
  health() {
    return { ...this.info, reporting: this.edgeLink, view: this.viewLink };
  }

  /** @param {() => void} fn @returns {() => void} */
  subscribe(fn) {
    this.listeners.add(fn);
    return () => this.listeners.delete(fn);
  }

  emit() {
    for (const fn of this.listeners) fn();
  }

  close() {
    for (const c of this.closers) c();
  }
}
