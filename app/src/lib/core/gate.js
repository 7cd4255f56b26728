/**
 * May a command control be used right now? One rule for every page (DESIGN.md "Grants", "The page kit"):
 * never while offline or while the ROS link is down (nothing is queued to send later), only for features
 * whose commands the role was granted (/api/config `commands`), and motion commands only with the lease.
 * The server enforces all of this too; the gate only keeps the UI honest and says why a control is off.
 */

import { m } from '$lib/paraglide/messages.js';

/**
 * @typedef {object} GateInput
 * @property {boolean} offline  the BFF is unreachable
 * @property {'connecting' | 'connected' | 'disconnected'} [conn]  the ROS link; omit for HTTP-only commands
 * @property {string} [feature]  the feature whose commands these are
 * @property {string[] | undefined} [commands]  /api/config `commands` (absent: not checked here)
 * @property {boolean} [needsLease]  the command can move the robot
 * @property {boolean} [holdsLease]  this session holds the control lease
 */

/** @typedef {{ ok: true, reason: '' } | { ok: false, reason: string }} Gate */

/** @param {GateInput} g @returns {Gate} */
export function commandGate(g) {
  if (g.offline) return { ok: false, reason: m.core_gate_offline() };
  if (g.conn !== undefined && g.conn !== 'connected') {
    return { ok: false, reason: g.conn === 'connecting' ? m.core_gate_connecting() : m.core_gate_not_connected() };
  }
  if (g.feature && Array.isArray(g.commands) && !g.commands.includes(g.feature)) {
    return { ok: false, reason: m.core_gate_role() };
  }
  if (g.needsLease && !g.holdsLease) return { ok: false, reason: m.core_gate_take_control() };
  return { ok: true, reason: '' };
}

/** @type {Gate} */
export const OPEN_GATE = { ok: true, reason: '' };
