// A role's rosbridge grants, derived from the feature list and the cell file: pure functions, tested on their own.
// - every role reads the operation mode (the shell shows it everywhere);
// - a role reads what the features of its pages read;
// - it sends a feature's commands where `roles.<role>.commands` lists that feature;
// - every role that sees any page may call the robot stop (the page kit's "Stop robot", a feature's `robotStop`):
//   whoever watches the cell must be able to stop it, moving it or not; that one call, nothing that moves;
// - the features' other stop names (process stop/pause, routines stop) go to roles that see a page that can
//   move the robot; no stop name is ever lease-gated;
// - `roles.<role>.ros` adds raw grants (an escape hatch).
import { namesOf, mergeNames, isEmpty } from '../features/feature.js';

/** @typedef {import('../features/feature.js').Feature} Feature @typedef {import('../config/cell-types.js').Cell} Cell */

/** @param {Feature[]} features @param {string} id */
const byId = (features, id) => features.find((f) => f.id === id);

/** Does any page of the role belong to a feature that can move the robot? */
export function mayMoveRobot(/** @type {Cell} */ cell, /** @type {Feature[]} */ features, /** @type {string} */ role) {
  return (cell.roles[role]?.pages || []).some((p) => {
    const f = byId(features, p);
    return !!f && !isEmpty(namesOf(f, 'motion', cell));
  });
}

/** Does the role see any page of the cell? (Such a role gets the robot stop.) */
export function seesAnyPage(/** @type {Cell} */ cell, /** @type {string} */ role) {
  return (cell.roles[role]?.pages || []).some((p) => cell.pages.some((x) => x.id === p));
}

/** The cell's robot stop (the first feature with a `robotStop` whose section the cell has), or null. */
export function cellRobotStop(/** @type {Cell} */ cell, /** @type {Feature[]} */ features) {
  const f = features.find((x) => x.robotStop && (!x.schema || cell[x.id] !== undefined));
  return f?.robotStop ?? null;
}

/** Topics whose publishes the BFF stamps as it lets them through (features' `stamped`, for the cell's sections). */
export function stampedTopics(/** @type {Cell} */ cell, /** @type {Feature[]} */ features) {
  return features.filter((f) => f.stamped && (!f.schema || cell[f.id] !== undefined)).flatMap((f) => f.stamped ?? []);
}

/** @param {Cell} cell @param {Feature[]} features */
export function stopNames(cell, features) {
  return mergeNames(...features.map((f) => namesOf(f, 'stop', cell)));
}

/**
 * @param {Cell} cell @param {Feature[]} features @param {string} role
 * @returns {Required<import('../features/feature.js').RosNames>}
 */
export function grantsFor(cell, features, role) {
  const def = cell.roles[role];
  if (!def) return mergeNames();
  const om = cell.operation_mode;
  /** @type {import('../features/feature.js').RosNames[]} */
  const parts = [{ subscribe: [om.topic], call_service: om.get_service ? [om.get_service] : [] }];
  for (const p of def.pages) {
    const f = byId(features, p);
    if (f) parts.push(namesOf(f, 'reads', cell));
  }
  for (const c of def.commands || []) {
    const f = byId(features, c);
    if (f && def.pages.includes(c)) parts.push(namesOf(f, 'commands', cell), namesOf(f, 'motion', cell));
  }
  if (mayMoveRobot(cell, features, role)) parts.push(stopNames(cell, features));
  const robotStop = robotStopFor(cell, features, role);
  if (robotStop) parts.push({ call_service: [robotStop.service] });
  parts.push(def.ros || {});
  return mergeNames(...parts);
}

/** Names whose publish or call needs the control lease: every feature's motion commands. */
export function motionNames(/** @type {Cell} */ cell, /** @type {Feature[]} */ features) {
  return mergeNames(...features.map((f) => namesOf(f, 'motion', cell)));
}

/**
 * The service behind the app's "Stop robot" button, for every role that sees any page (a role that never moves
 * the robot still stops it: it may be the one standing next to the cell). Never lease-gated.
 */
export function robotStopFor(/** @type {Cell} */ cell, /** @type {Feature[]} */ features, /** @type {string} */ role) {
  return seesAnyPage(cell, role) ? cellRobotStop(cell, features) : null;
}

/**
 * The features' argument checks as one function (the op guard calls it for every op the grants allow).
 * @param {Cell} cell @param {Feature[]} features
 * @returns {(role: string, op: string, target: string, msg: any) => string | null}
 */
export function argumentChecks(cell, features) {
  const checks = features.filter((f) => f.checkArgs && cell[f.id] !== undefined);
  return (role, op, target, msg) => {
    for (const f of checks) {
      const why = /** @type {NonNullable<Feature['checkArgs']>} */ (f.checkArgs)(cell[f.id], role, op, target, msg);
      if (why) return why;
    }
    return null;
  };
}
