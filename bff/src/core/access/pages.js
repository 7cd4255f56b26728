// What a role may see of the cell file: pure functions of (cell, features, role).
import { robotStopFor } from './grants.js';

/** @typedef {import('../config/cell-types.js').Cell} Cell @typedef {import('../features/feature.js').Feature} Feature */

/** @param {Cell} cell @param {string} role @returns {{id: string, title: string}[]} */
export function pagesFor(cell, role) {
  const allowed = new Set(cell.roles[role]?.pages || []);
  return cell.pages.filter((p) => allowed.has(p.id)).map(({ id, title }) => ({ id, title }));
}

/** @param {Cell} cell @param {string} role @param {string} pageId */
export function mayViewPage(cell, role, pageId) {
  return (cell.roles[role]?.pages || []).includes(pageId);
}

/**
 * The cell file as the UI of this role needs it: each feature's view of its section, only for the features
 * whose pages the role sees.
 * @param {Cell} cell @param {Feature[]} features @param {string} role
 */
export function configFor(cell, features, role) {
  const { topic, type, modes } = cell.operation_mode;
  const def = cell.roles[role];
  /** @type {Record<string, unknown>} */
  const views = {};
  for (const f of features) {
    if (!f.view || !mayViewPage(cell, role, f.id) || (f.schema && cell[f.id] === undefined)) continue;
    views[f.id] = f.view(cell[f.id], role, cell);
  }
  return {
    cell: { id: cell.cell.id, name: cell.cell.name, description: cell.cell.description || '' },
    role,
    pages: pagesFor(cell, role),
    operation_mode: { topic, type, modes },
    features: views,
    commands: (def?.commands || []).filter((c) => def.pages.includes(c)),
    // heartbeat_timeout_s: the app heartbeats well within it and tells a lost link from a lost lease by it.
    control: { take_over: def?.take_over === true, heartbeat_timeout_s: cell.control?.heartbeat_timeout_s ?? 2 },
    stop: robotStopFor(cell, features, role),
  };
}
