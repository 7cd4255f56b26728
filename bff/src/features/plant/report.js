// What a cell says about itself on the plant's broker: the latest of its state topics, as Sparkplug metric values.
// Plain data in, plain data out (the ROS link and the MQTT link live elsewhere), so it is tested on its own.
import { cellMetrics } from './sparkplug.js';

/** @typedef {import('./sparkplug.js').MetricValue} MetricValue */

/**
 * The cell's shape and the state topics it reads, from the cell file (only what the cell has).
 * @param {any} cell
 * @returns {{groups: string[], modules: string[], topics: {topic: string, type: string}[]}}
 */
export function cellShape(cell) {
  const groups = (cell.manual?.groups ?? []).map((/** @type {any} */ g) => String(g.name));
  const modules = (Array.isArray(cell.modules) ? cell.modules : []).map((/** @type {any} */ m) => String(m.name));
  /** @type {{topic: string, type: string}[]} */
  const topics = [];
  if (cell.operation_mode?.topic) topics.push({ topic: cell.operation_mode.topic, type: cell.operation_mode.type || 'cell_msgs/OperationMode' });
  if (cell.alarms) topics.push({ topic: '/cell/alarms/status', type: 'cell_msgs/SafetyStatus' });
  if (cell.process) topics.push({ topic: '/cell/process/state', type: 'cell_msgs/ProcessState' });
  if (modules.length) topics.push({ topic: '/cell/modules/state', type: 'cell_msgs/ModuleStates' });
  for (const g of groups) topics.push({ topic: `/cell/manual/${g}/state`, type: 'cell_msgs/RobotState' });
  return { groups, modules, topics };
}

export class CellReport {
  /** @param {any} cell @param {{url?: string}} [o] */
  constructor(cell, { url = '' } = {}) {
    this.shape = cellShape(cell);
    this.defs = cellMetrics(this.shape);
    this.name = String(cell.cell?.name ?? cell.cell?.id ?? '');
    this.url = url;
    this.modeTopic = cell.operation_mode?.topic ?? null;
    this.ros = false;
    /** @type {Map<string, any>} */
    this.latest = new Map();
  }

  /** The ROS link went up or down: while down nothing is known of the cell (its values are reported as null). */
  setRos(up) {
    this.ros = up;
    if (!up) this.latest.clear();
  }

  /** @param {string} topic @param {any} msg */
  onMessage(topic, msg) {
    if (msg && typeof msg === 'object') this.latest.set(topic, msg);
  }

  /** @returns {Record<string, MetricValue>} */
  values() {
    /** @type {Record<string, MetricValue>} */
    const v = { 'Properties/Name': this.name, 'Properties/URL': this.url, 'ROS/Connected': this.ros };
    const str = (/** @type {any} */ x) => (typeof x === 'string' ? x : null);
    const num = (/** @type {any} */ x) => (typeof x === 'number' && Number.isFinite(x) ? x : null);
    const mode = this.modeTopic ? this.latest.get(this.modeTopic) : undefined;
    v.Mode = str(mode?.mode);
    const s = this.latest.get('/cell/alarms/status');
    v['Safety/Status'] = str(s?.status);
    v['Alarms/Active'] = num(s?.active_count);
    v['Alarms/Most severe'] = str(s?.text);
    v['Alarms/Highest severity'] = num(s?.highest_severity);
    const p = this.latest.get('/cell/process/state');
    v['Process/State'] = str(p?.state);
    const running = p && p.state !== 'idle' && Number.isInteger(p.current) && p.current >= 0;
    v['Process/Operation'] = p ? (running ? str(p.operations?.[p.current]) ?? '' : '') : null;
    v['Process/Cycles done'] = num(p?.cycles_done);
    v['Process/Last cycle time'] = num(p?.last_cycle_s);
    for (const g of this.shape.groups) {
      const r = this.latest.get(`/cell/manual/${g}/state`);
      v[`Robot/${g}/Connected`] = typeof r?.connected === 'boolean' ? r.connected : null;
      v[`Robot/${g}/Mode`] = str(r?.robot_mode);
    }
    const mods = this.latest.get('/cell/modules/state')?.modules;
    for (const name of this.shape.modules) {
      const m = Array.isArray(mods) ? mods.find((/** @type {any} */ x) => x?.name === name) : undefined;
      v[`Modules/${name}`] = str(m?.state);
    }
    return v;
  }
}
