/**
 * The Process page's plain logic: the ROS names, what the process node's state means for the controls, the
 * status panel's values. No Svelte, no ROS: tests import it directly. Texts come from messages/process, numbers
 * in the user's locale.
 */
import { m } from '$lib/paraglide/messages.js';
import { paramsOf, saidText } from '../../core/said.js';
import { fmtNumber, fmtFixed, cellText } from '$lib/core/i18n.js';

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

/** Every state has a label (in the user's language) and a tone (colour is never the only signal). */
export const STATE_VIEW = Object.freeze({
  idle: { tone: 'neutral', get label() { return m.process_state_idle(); } },
  running: { tone: 'ok', get label() { return m.process_state_running(); } },
  pausing: { tone: 'warn', get label() { return m.process_state_pausing(); } },
  paused: { tone: 'warn', get label() { return m.process_state_paused(); } },
  stopping: { tone: 'warn', get label() { return m.process_state_stopping(); } },
  error: { tone: 'danger', get label() { return m.process_state_error(); } },
  unknown: { tone: 'neutral', get label() { return m.process_state_unknown(); } },
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
 * @param {import('../../core/said.js').Rename} [rename]  how the page names a parameter (an operation's title)
 * @returns {ProcessView}
 */
export function processView(msg, fallbackOperations = [], rename) {
  const ops = Array.isArray(msg?.operations) && msg.operations.length ? msg.operations.map(String) : [...fallbackOperations];
  return {
    state: msg ? stateName(msg.state) : 'unknown',
    operations: ops,
    current: msg ? num(msg.current, -1) : -1,
    step: said(msg?.step, msg?.step_code, msg?.step_params, rename),
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
    message: said(msg?.message, msg?.message_code, msg?.message_params, rename),
  };
}

/**
 * A text of the node's state in the user's language (its code and parameters), else its English.
 * @param {unknown} text @param {unknown} code @param {unknown} params @param {import('../../core/said.js').Rename} [rename]
 */
function said(text, code, params, rename) {
  const t = String(text ?? '');
  return typeof code === 'string' && code ? saidText(code, paramsOf(params), t, rename) : t;
}

/**
 * How the process's texts name a parameter: an operation by its title in the cell file, a step's own text or note
 * by the cell file's text in the user's language (the node says the English; `{n}` in it: the pose-table entry's
 * number, the same in every language).
 * @param {Record<string, unknown>} titles  title by name
 * @param {unknown[]} [stepTexts]  the steps' texts given per language (/api/config features.process.step_texts)
 * @returns {import('../../core/said.js').Rename}
 */
export function processNames(titles, stepTexts = []) {
  return (key, value) => (key === 'operation' ? operationText(value, titles)
    : key === 'text' || key === 'note' ? stepText(value, stepTexts) : undefined);
}

const REGEX_SPECIAL = /[.*+?^${}()|[\]\\]/g;

/**
 * The cell file's text, in the user's language, of a step text the node said in English; undefined: none given.
 * @param {string} english @param {unknown[]} stepTexts
 * @returns {string | undefined}
 */
export function stepText(english, stepTexts) {
  for (const t of Array.isArray(stepTexts) ? stepTexts : []) {
    const en = t && typeof t === 'object' ? /** @type {Record<string, unknown>} */ (t).en : undefined;
    if (typeof en !== 'string') continue;
    if (en === english) return cellText(t);
    if (!en.includes('{n}')) continue;
    const match = new RegExp(`^${en.split('{n}').map((p) => p.replace(REGEX_SPECIAL, '\\$&')).join('(\\d+)')}$`).exec(english);
    if (match) return cellText(t).replaceAll('{n}', match[1]);
  }
  return undefined;
}

/** @param {ProcessStateName} s */
export const isActive = (s) => s === 'running' || s === 'pausing' || s === 'paused' || s === 'stopping';

/**
 * Why Start and Run step are off while the process is active ("The process is running").
 * @param {ProcessStateName} s
 */
function busyReason(s) {
  switch (s) {
    case 'running': return m.process_busy_running();
    case 'pausing': return m.process_busy_pausing();
    case 'paused': return m.process_busy_paused();
    case 'stopping': return m.process_busy_stopping();
    default: return m.process_not_running(); // (not active: Start and Run step are not off for this reason)
  }
}

/**
 * Which controls apply in a state (before the gates: grant, lease, link). Each is { ok, reason }.
 * @param {ProcessView} v
 * @param {number} selected  the operation chosen for Run step, -1 none
 */
export function controls(v, selected) {
  const s = v.state;
  const known = s !== 'unknown';
  const why = (/** @type {boolean} */ ok, /** @type {string} */ reason) => (ok ? { ok: true, reason: '' } : { ok: false, reason });
  const busy = busyReason(s);
  const waiting = m.process_waiting_node();
  return {
    start: why(known && !isActive(s), known ? busy : waiting),
    // One toggle: "Pause" while running, "Resume" while paused (`resume` says which, the label is the user's language).
    toggle: s === 'paused'
      ? { resume: true, label: m.process_resume(), ...why(true, '') }
      : { resume: false, label: m.process_pause(), ...why(s === 'running', s === 'pausing' ? m.process_pausing_at_end() : m.process_not_running()) },
    step: why(known && !isActive(s) && selected >= 0 && selected < v.operations.length,
      !known ? waiting : isActive(s) ? busy : m.process_choose_operation_first()),
    stop: why(isActive(s), m.process_not_running()),
    dryRun: why(known && !isActive(s), known ? m.process_dry_run_when_stopped() : waiting),
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
  if (s.includes(':')) return m.process_start_question_groups({ configs: s });
  return s ? m.process_start_question({ configuration: s }) : m.process_start_question_unnamed();
}

/** @param {number} s seconds @returns {string} "12.3 s", "2 min 5 s" (numbers in the user's locale) */
export function formatSeconds(s) {
  if (!Number.isFinite(s) || s <= 0) return '–';
  if (s < 60) return `${fmtFixed(s, 1)} s`;
  const min = Math.floor(s / 60);
  return `${fmtNumber(min)} min ${fmtNumber(Math.round(s - min * 60))} s`;
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
  return elapsedS > activeS && elapsed !== active ? m.process_with_pauses({ active, elapsed }) : active;
}

/** @param {ProcessView} v @returns {string} "Cycle 2 of 5" / "Cycle 2" / "Not started" */
export function cycleText(v) {
  if (v.cycle <= 0) return m.process_not_started();
  const cycle = fmtNumber(v.cycle);
  return v.cyclesTarget > 0 ? m.process_cycle_of({ cycle, target: fmtNumber(v.cyclesTarget) }) : m.process_cycle_n({ cycle });
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
  if (typeof v === 'number') t = Number.isInteger(v) ? fmtNumber(v, { useGrouping: false }) : fmtFixed(v, Math.abs(v) >= 100 ? 1 : 2);
  else if (typeof v === 'boolean') t = v ? m.process_yes() : m.process_no();
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

/**
 * An operation as the page shows it: its title from the cell file (a text per language, `process.operations[].title`)
 * in the user's language, else its name. The node's state and the cell file name operations alike.
 * @param {unknown} name  the operation's name
 * @param {Record<string, unknown>} [titles]  title by name (/api/config features.process.titles)
 * @returns {string}
 */
export function operationText(name, titles = {}) {
  if (typeof name === 'string' && titles && Object.hasOwn(titles, name)) return cellText(titles[name]) || name;
  return cellText(name);
}

/**
 * A cell-file text as an attribute value that does not depend on the language (its English, else any).
 * @param {unknown} text @returns {string}
 */
export function rawText(text) {
  if (typeof text === 'string') return text;
  if (!text || typeof text !== 'object') return '';
  const byLang = /** @type {Record<string, unknown>} */ (text);
  const v = typeof byLang.en === 'string' ? byLang.en : Object.values(byLang).find((x) => typeof x === 'string');
  return typeof v === 'string' ? v : '';
}
