/**
 * The Routines page's plain logic: ROS names, the draft being recorded (add, delete, reorder), step texts, name
 * rules (the node checks them too), and the run state. No Svelte, no ROS: tests import it directly. The texts come
 * from messages/routines, the numbers in the user's locale.
 */

import { m } from '$lib/paraglide/messages.js';
import { cellText, fmtFixed } from '../../core/i18n.js';
import { paramsOf, saidText } from '../../core/said.js';

export const FEATURE_ID = 'routines';

export const NAMES = Object.freeze({
  list: { service: '/cell/routines/list', type: 'cell_msgs/ListRoutines' },
  record: { service: '/cell/routines/record', type: 'cell_msgs/RecordStep' },
  save: { service: '/cell/routines/save', type: 'cell_msgs/SaveRoutine' },
  rename: { service: '/cell/routines/rename', type: 'cell_msgs/RenameRoutine' },
  remove: { service: '/cell/routines/delete', type: 'cell_msgs/DeleteRoutine' },
  run: { service: '/cell/routines/run', type: 'cell_msgs/RunRoutine' },
  stop: { service: '/cell/routines/stop', type: 'std_srvs/Trigger' },
  state: { topic: '/cell/routines/state', type: 'cell_msgs/RoutineRunState' },
  log: { topic: '/cell/routines/log', type: 'cell_msgs/LogEntries' },
  groups: { service: '/cell/manual/groups', type: 'cell_msgs/GetMotionGroups' },
  // The chosen group's driver state (its live TCP pose): /cell/manual/<group>/state, see robotTopic.
});

/** The driver state topic of a motion group (the live pose shown while teaching). @param {string} group */
export const robotTopic = (group) => `/cell/manual/${group}/state`;
export const ROBOT_TYPE = 'cell_msgs/RobotState';

/** A routine run may take a while: the run call waits this long for its answer. */
export const RUN_TIMEOUT_MS = 300_000;

/**
 * @typedef {object} Step
 * @property {'pose' | 'action'} kind
 * @property {number[]} pose  x, y, z (m), rx, ry, rz (rad)
 * @property {number[]} joints  rad
 * @property {string} tool
 * @property {string} action
 */

/** @param {any} s @returns {Step} a step as the node's messages carry it */
export function normalizeStep(s) {
  const nums = (/** @type {any} */ a) => (Array.isArray(a) ? a.map(Number) : []);
  return {
    kind: s?.kind === 'action' ? 'action' : 'pose',
    pose: nums(s?.pose),
    joints: nums(s?.joints),
    tool: String(s?.tool ?? ''),
    action: String(s?.action ?? ''),
  };
}

/** @param {number} x @param {number} [d] */
const fixed = (x, d = 1) => (Number.isFinite(x) ? fmtFixed(x, d) : '?');

/**
 * A tool action as the Manual page's button names it: the cell file's title in the user's language (the routines
 * view's `action_titles`, by "tool/action"), else "Gripper close".
 * @param {string} tool @param {string} action @param {Record<string, any>} [titles]
 */
export function actionText(tool, action, titles) {
  const title = titles && typeof titles === 'object' ? titles[`${tool}/${action}`] : undefined;
  return (title && cellText(title)) || `${capitalize(tool)} ${action}`.trim();
}

/** "Pose: x 412.3, y -120.0, z 230.5 mm" or "Gripper close". @param {Step} s @param {Record<string, any>} [titles] */
export function stepText(s, titles) {
  if (s.kind === 'action') return actionText(s.tool, s.action, titles);
  const [x, y, z] = s.pose.map((v) => v * 1000);
  return m.routines_step_pose({ x: fixed(x), y: fixed(y), z: fixed(z) });
}

/** @param {string} s */
export const capitalize = (s) => (s ? s[0].toUpperCase() + s.slice(1) : s);

/** @param {Step[]} steps @param {number} i @returns {Step[]} */
export function removeStep(steps, i) {
  return steps.filter((_, k) => k !== i);
}

/** Move step i by `by` (-1 up, +1 down); out of range leaves the list as it is. @param {Step[]} steps @param {number} i @param {number} by */
export function moveStep(steps, i, by) {
  const j = i + by;
  if (i < 0 || i >= steps.length || j < 0 || j >= steps.length) return steps;
  const out = [...steps];
  [out[i], out[j]] = [out[j], out[i]];
  return out;
}

/**
 * The name rule, checked before sending (the node checks it again and has the last word): 1-64 characters of
 * ASCII letters, digits, space, - _ . (the name is the file's name: one spelling on every file system), not starting
 * with a dot, not starting or ending with a space.
 * @param {string} name @param {string[]} existing
 * @returns {string} the problem, '' when the name is fine
 */
export function nameProblem(name, existing = []) {
  const n = name.trim();
  if (!n) return m.routines_name_missing();
  if (n.length > 64) return m.routines_name_too_long();
  if (!/^[A-Za-z0-9_\-. ]+$/.test(n) || n.startsWith('.')) return m.routines_name_chars();
  if (existing.includes(n)) return m.routines_name_exists({ name: n });
  return '';
}

/**
 * @typedef {object} RoutineView
 * @property {string} name
 * @property {string} group
 * @property {string} tool
 * @property {Step[]} steps
 * @property {number | null} modified  ms since the epoch
 * @property {string} error  the file could not be read
 */

/** @param {any} r @returns {RoutineView} */
export function routineView(r) {
  const secs = Number(r?.modified?.secs ?? r?.modified?.sec);
  return {
    name: String(r?.name ?? ''),
    group: String(r?.group ?? ''),
    tool: String(r?.tool ?? ''),
    steps: Array.isArray(r?.steps) ? r.steps.map(normalizeStep) : [],
    modified: Number.isFinite(secs) && secs > 0 ? secs * 1000 : null,
    // Why the file cannot be read or run, in the user's language (the node's English without a code).
    error: saidText(String(r?.error_code ?? ''), paramsOf(r?.error_params), String(r?.error ?? '')),
  };
}

/** @param {RoutineView} r @returns {string} "3 steps: 2 poses, 1 action · arm · gripper" */
export function routineSummary(r) {
  if (r.error) return r.error;
  const poses = r.steps.filter((s) => s.kind === 'pose').length;
  const actions = r.steps.length - poses;
  /** @type {string[]} */
  const parts = [m.routines_summary_counts({
    steps: m.routines_n_steps({ count: r.steps.length }),
    poses: m.routines_n_poses({ count: poses }),
    actions: m.routines_n_actions({ count: actions }),
  })];
  if (r.group) parts.push(r.group);
  if (r.tool) parts.push(r.tool);
  return parts.join(' · ');
}

/**
 * @typedef {{ name: string, state: 'idle' | 'running' | 'stopping', step: number, total: number, message: string }} RunView
 */
/** @param {any} msg  cell_msgs/RoutineRunState @returns {RunView} */
export function runView(msg) {
  const state = msg?.state === 'running' || msg?.state === 'stopping' ? msg.state : 'idle';
  return { name: String(msg?.name ?? ''), state, step: Number(msg?.step) || 0, total: Number(msg?.total) || 0, message: saidText(String(msg?.message_code ?? ''), paramsOf(msg?.message_params), String(msg?.message ?? '')) };
}

/**
 * The tools and their actions the recorder offers: the routines section's tools, with the actions the driver
 * reports for them (cell_msgs/GetMotionGroups `tools`).
 * @param {string[]} allowed  the routines section's tools
 * @param {any} groupsAnswer  the driver's answer, or null
 * @returns {{ name: string, actions: string[] }[]}
 */
export function toolChoices(allowed, groupsAnswer) {
  const tools = Array.isArray(groupsAnswer?.tools) ? groupsAnswer.tools : [];
  return allowed.map((name) => {
    const t = tools.find((/** @type {any} */ x) => x?.name === name);
    return { name, actions: Array.isArray(t?.actions) ? t.actions.map(String) : [] };
  });
}

/**
 * The tools a routine for `group` may use. A tool's group: the page's section (`tool_groups`, from the cell file),
 * else the driver's answer (ToolInfo.group), else the cell's first group.
 * @param {{ name: string, actions: string[] }[]} choices  from toolChoices
 * @param {string} group
 * @param {{ toolGroups?: Record<string, string>, groupsAnswer?: any, firstGroup?: string }} [o]
 * @returns {{ name: string, actions: string[] }[]}
 */
export function toolsOfGroup(choices, group, { toolGroups = {}, groupsAnswer = null, firstGroup = '' } = {}) {
  const driver = Array.isArray(groupsAnswer?.tools) ? groupsAnswer.tools : [];
  const first = firstGroup || (Array.isArray(groupsAnswer?.groups) ? String(groupsAnswer.groups[0]?.name ?? '') : '');
  return choices.filter((t) => {
    const fromDriver = driver.find((/** @type {any} */ x) => x?.name === t.name)?.group;
    const g = (toolGroups && typeof toolGroups[t.name] === 'string' && toolGroups[t.name])
      || (typeof fromDriver === 'string' && fromDriver) || first;
    return g === group;
  });
}

/** The live TCP pose for the recorder: "x 412.3  y -120.0  z 230.5 mm". @param {number[] | undefined} pose */
export function poseText(pose) {
  if (!Array.isArray(pose) || pose.length < 6) return '–';
  const [x, y, z, rx, ry, rz] = pose;
  return `x ${fixed(x * 1000)}  y ${fixed(y * 1000)}  z ${fixed(z * 1000)} mm · rx ${fixed(rx, 3)}  ry ${fixed(ry, 3)}  rz ${fixed(rz, 3)} rad`;
}
