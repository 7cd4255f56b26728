// What a feature slice is, for the BFF: one object per feature, listed in bff/src/features/index.js.
// The app, /api/config, the OpenAPI document, the cell-file schema and the per-op grants are built by walking
// that list, so a new feature adds its folder and one list entry and touches no other feature.
import fs from 'node:fs';
import path from 'node:path';
import { REPO_ROOT } from '../config/env.js';

/**
 * ROS names by rosbridge grant kind. Plain names or glob patterns ("*" any run, "?" one character).
 * @typedef {{subscribe?: string[], publish?: string[], call_service?: string[], advertise?: string[],
 *   advertise_service?: string[]}} RosNames
 */

/**
 * What a feature's routes get from the core.
 * @typedef {object} FeatureDeps
 * @property {import('../config/cell-types.js').Cell} cell
 * @property {any} section the feature's section of the cell file (undefined when the cell file has none)
 * @property {string} cellFile path of the cell file
 * @property {import('../config/env.js').Env} env
 * @property {import('../auth/users.js').UserStore} users
 * @property {import('../audit/audit-log.js').AuditLog} audit
 * @property {() => Promise<object>} healthReport
 * @property {import('express').RequestHandler[]} guard session + "the role sees this feature's page"
 * @property {(m: string) => void} log
 * @property {(fn: () => void) => void} onClose a background service the feature runs is stopped with the BFF
 * @property {(key: string, fn: () => object) => void} addHealth a part of the health report (GET /api/health, System page)
 */

/**
 * @typedef {object} Feature
 * @property {string} id feature id = page id = cell-file section = folder name = ROS namespace /cell/<id>/
 * @property {string} title default page title (the cell file's `pages[].title` wins)
 * @property {object} [schema] JSON Schema of its cell-file section (may $ref the core schema's $defs)
 * @property {boolean} [sectionRequired] a cell that shows the page must have the section (default: when it has a schema)
 * @property {(section: any, cell: import('../config/cell-types.js').Cell) => string[]} [check]
 *   cross-references its schema cannot express; each problem names the field ("modules[0].roles[1]: ...")
 * @property {(section: any, role: string, cell: import('../config/cell-types.js').Cell) => any} [view]
 *   what the UI of a role that sees the page gets from the section (GET /api/config `features.<id>`)
 * @property {(section: any, cell: import('../config/cell-types.js').Cell) => RosNames} [reads]
 *   what a role that sees the page may read
 * @property {(section: any, cell: import('../config/cell-types.js').Cell) => RosNames} [commands]
 *   what a role whose `commands` list the feature may send
 * @property {(section: any, cell: import('../config/cell-types.js').Cell) => RosNames} [motion]
 *   the commands that move the robot: they also need the control lease
 * @property {(section: any, cell: import('../config/cell-types.js').Cell) => RosNames} [stop]
 *   what stops the robot: granted to every role that sees a page that can move it, never lease-gated
 * @property {string[]} [stamped] hold-to-run heartbeat topics: their messages have a `stamp` (time) field, which
 *   the BFF sets to the moment it lets each one through, so the driver can drop heartbeats that arrive late
 * @property {{service: string, type: string}} [robotStop] the service behind the app's "Stop robot" button:
 *   granted to every role that sees any page (moving the robot or not), never lease-gated
 * @property {(section: any, role: string, op: string, target: string, msg: any) => string | null} [checkArgs]
 *   for ops the grants already allow: a reason to refuse this one for its arguments (e.g. a module the role
 *   may not launch), or null
 * @property {(deps: FeatureDeps) => import('express').Router} [routes] HTTP routes under /api/<id>/
 * @property {Record<string, object>} [openapi] OpenAPI paths of those routes
 */

/** The grant kinds a feature can name. */
export const KINDS = /** @type {const} */ (['subscribe', 'publish', 'call_service', 'advertise', 'advertise_service']);

/** @param {Feature} f @returns {Feature} */
export const defineFeature = (f) => f;

/**
 * Names a feature function gives for a cell, empty when the feature lacks it or the cell lacks the section.
 * @param {Feature} f @param {'reads'|'commands'|'motion'|'stop'} what @param {import('../config/cell-types.js').Cell} cell
 * @returns {RosNames}
 */
export function namesOf(f, what, cell) {
  const fn = f[what];
  if (!fn || (f.schema && cell[f.id] === undefined)) return {};
  return fn(cell[f.id], cell) || {};
}

/** @param {RosNames[]} list @returns {Required<RosNames>} */
export function mergeNames(...list) {
  const out = /** @type {Required<RosNames>} */ (Object.fromEntries(KINDS.map((k) => [k, []])));
  for (const n of list) for (const k of KINDS) for (const x of n?.[k] || []) if (!out[k].includes(x)) out[k].push(x);
  return out;
}

/** Does this feature have any name of that kind? @param {RosNames} n */
export const isEmpty = (n) => KINDS.every((k) => !(n[k] || []).length);

/** A feature's section schema from config/features/<id>.schema.json. @param {string} id @returns {object} */
export function featureSchema(id) {
  return JSON.parse(fs.readFileSync(path.join(REPO_ROOT, 'config/features', `${id}.schema.json`), 'utf8'));
}
