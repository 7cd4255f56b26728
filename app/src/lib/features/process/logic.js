/**
 * The Process page's plain logic: the ROS names, what the process node's state means for the controls, the
 * status panel's values. No Svelte, no ROS: tests import it directly.
 */

export const FEATURE_ID = 'process';

export const NAMES = Object.freeze({
  state: { topic: '/cell/process/state', type: 'cell_msgs/ProcessState' },
  log: { topic: '/cell/process/log', type: 'cell_msgs/LogEntries' },
  start: { service: '/cell/process/start', type: 'cell_msgs/ProcessStart' },
  stop: { service: '/cell/process/stop', type: 'std_srvs/Trigger' },
  pause: { service: '/cell/process/pause', type: 'std_srvs/Trigger' },
  resume: { service: '/cell/process/resume', type: 'std_srvs/Trigger' },
  step: { service: '/cell/process/step', type: 'cell_msgs/ProcessStep' },
  dryRun: { service: '/cell/process/set_dry_run', type: 'std_srvs/SetBool' },
});

/** The state is published at ~2 Hz while running and on every change (latched): older than this while running is stale. */
export const STATE_PERIOD_MS = 3000;
/** A status field's topic older than this is marked stale. */
export const FIELD_PERIOD_MS = 5000;

/** @typedef {'idle' | 'running' | 'pausing' | 'paused' | 'stopping' | 'error' | 'unknown'} ProcessStateName */

/** Every state has a label and a tone (colour is never the only signal). */
export const STATE_VIEW = Object.freeze({
  idle: { tone: 'neutral', label: 'Idle' },
  running: { tone: 'ok', label: 'Running' },
  pausing: { tone: 'warn', label: 'Pausing at step end' },
  paused: { tone: 'warn', label: 'Paused' },
  stopping: { tone: 'warn', label: 'Stopping' },
  error: { tone: 'danger', label: 'Error' },
  unknown: { tone: 'neutral', label: 'Unknown' },
});

/**
 * @typedef {object} ProcessView
 * @property {ProcessStateName} state
 * @property {string[]} operations
 * @property {number} current  index of the running (or next) operation, -1 none
 * @property {string} step  the running step's text
 * @property {number} stepIndex  0-based
 * @property {number} stepCount
 * @property {boolean} dryRun
 * @property {string} runMode  'cycle' or 'step'
 * @property {number} cycle
 * @property {number} cyclesTarget  0: until stopped
 * @property {number} cyclesDone
 * @property {number} cycleTimeS  the current cycle's active time (paused time excluded)
 * @property {number} cycleElapsedS  the same, paused time included
 * @property {number} lastCycleS  the last completed cycle's active time
 * @property {number} lastCycleElapsedS  the same, paused time included
 * @property {boolean} atStart
 * @property {string} startConfiguration
 * @property {string} message
 */

/** @param {any} s @returns {ProcessStateName} */
function stateName(s) {
  return ['idle', 'running', 'pausing', 'paused', 'stopping', 'error'].includes(s) ? s : 'unknown';
}

/** @param {any} v @param {number} [d] */
const num = (v, d = 0) => (Number.isFinite(Number(v)) ? Number(v) : d);

/**
 * @param {any} msg  cell_msgs/ProcessState or null
 * @param {string[]} [fallbackOperations]  the cell file's names (before the first message)
 * @returns {ProcessView}
 */
export function processView(msg, fallbackOperations = []) {
  const ops = Array.isArray(msg?.operations) && msg.operations.length ? msg.operations.map(String) : [...fallbackOperations];
  return {
    state: msg ? stateName(msg.state) : 'unknown',
    operations: ops,
    current: msg ? num(msg.current, -1) : -1,
    step: String(msg?.step ?? ''),
    stepIndex: num(msg?.step_index),
    stepCount: num(msg?.step_count),
    dryRun: !!msg?.dry_run,
    runMode: String(msg?.run_mode ?? ''),
    cycle: num(msg?.cycle),
    cyclesTarget: num(msg?.cycles_target),
    cyclesDone: num(msg?.cycles_done),
    cycleTimeS: num(msg?.cycle_time_s),
    cycleElapsedS: num(msg?.cycle_elapsed_s),
    lastCycleS: num(msg?.last_cycle_s),
    lastCycleElapsedS: num(msg?.last_cycle_elapsed_s),
    atStart: !!msg?.at_start,
    startConfiguration: String(msg?.start_configuration ?? ''),
    message: String(msg?.message ?? ''),
  };
}

/** @param {ProcessStateName} s */
export const isActive = (s) => s === 'running' || s === 'pausing' || s === 'paused' || s === 'stopping';

/**
 * Which controls apply in a state (before the gates: grant, lease, link). Each is { ok, reason }.
 * @param {ProcessView} v
 * @param {number} selected  the operation chosen for Run step, -1 none
 */
export function controls(v, selected) {
  const s = v.state;
  const known = s !== 'unknown';
  const why = (/** @type {boolean} */ ok, /** @type {string} */ reason) => (ok ? { ok: true, reason: '' } : { ok: false, reason });
  const busy = `The process is ${STATE_VIEW[s].label.toLowerCase()}`;
  return {
    start: why(known && !isActive(s), known ? busy : 'Waiting for the process node'),
    // One toggle: "Pause" while running, "Resume" while paused.
    toggle: s === 'paused'
      ? { label: 'Resume', ...why(true, '') }
      : { label: 'Pause', ...why(s === 'running', s === 'pausing' ? 'Pausing at the end of the step' : 'The process is not running') },
    step: why(known && !isActive(s) && selected >= 0 && selected < v.operations.length,
      !known ? 'Waiting for the process node' : isActive(s) ? busy : 'Choose an operation first'),
    stop: why(isActive(s), 'The process is not running'),
    dryRun: why(known && !isActive(s), known ? 'Change it while the process is stopped' : 'Waiting for the process node'),
  };
}

/**
 * Should Start ask first? When the cell names a start configuration and the robot is not there.
 * @param {ProcessView} v
 */
export function needsStartConfirmation(v) {
  return !!v.startConfiguration && !v.atStart;
}

/**
 * The question before a Start away from the start: one group ("home") or several ("left: home, right: home",
 * the node's wording for a start configuration per group).
 * @param {string} startConfiguration  the node's ProcessState.start_configuration
 */
export function startQuestion(startConfiguration) {
  const s = String(startConfiguration ?? '').trim();
  if (s.includes(':')) {
    return `The robots are not all at their start configurations (${s}). The first moves go there from where the arms are now. Start anyway?`;
  }
  return `The robot is not at ${s || 'its start configuration'}. The first move goes there from where the arm is now. Start anyway?`;
}

/** @param {number} s seconds @returns {string} */
export function formatSeconds(s) {
  if (!Number.isFinite(s) || s <= 0) return '–';
  if (s < 60) return `${s.toFixed(1)} s`;
  const m = Math.floor(s / 60);
  return `${m} min ${Math.round(s - m * 60)} s`;
}

/**
 * A cycle's time as the page shows it: the active time, and the time with pauses beside it when they differ
 * ("12.3 s (14.1 s with pauses)"). A node without the elapsed field (0) shows the active time alone.
 * @param {number} activeS  paused time excluded
 * @param {number} elapsedS  paused time included
 * @returns {string}
 */
export function cycleTimeText(activeS, elapsedS) {
  const active = formatSeconds(activeS);
  const elapsed = formatSeconds(elapsedS);
  return elapsedS > activeS && elapsed !== active ? `${active} (${elapsed} with pauses)` : active;
}

/** @param {ProcessView} v @returns {string} "Cycle 2 of 5" / "Cycle 2" / "Not started" */
export function cycleText(v) {
  if (v.cycle <= 0) return 'Not started';
  return v.cyclesTarget > 0 ? `Cycle ${v.cycle} of ${v.cyclesTarget}` : `Cycle ${v.cycle}`;
}

/**
 * A field of a message by a dotted path ("data", "wrench.force.x", "values[2]").
 * @param {any} msg @param {string | undefined} path
 * @returns {any} undefined when it is not there
 */
export function fieldAt(msg, path) {
  if (!path) return msg;
  let v = msg;
  for (const part of path.replace(/\[(\d+)\]/g, '.$1').split('.').filter(Boolean)) {
    if (v === null || v === undefined || typeof v !== 'object') return undefined;
    v = v[part];
  }
  return v;
}

/** @param {any} v @param {string} [unit] @returns {string} */
export function formatValue(v, unit) {
  let t;
  if (v === undefined || v === null) return '–';
  if (typeof v === 'number') t = Number.isInteger(v) ? String(v) : v.toFixed(Math.abs(v) >= 100 ? 1 : 2);
  else if (typeof v === 'boolean') t = v ? 'yes' : 'no';
  else if (typeof v === 'object') t = JSON.stringify(v);
  else t = String(v);
  return unit ? `${t} ${unit}` : t;
}

/** @param {any} v @returns {number} whole cycles, 0 = until stopped; NaN when not valid */
export function parseCycles(v) {
  const s = String(v ?? '').trim();
  if (s === '') return 0;
  if (!/^\d+$/.test(s)) return NaN;
  const n = Number(s);
  return n <= 100000 ? n : NaN;
}
