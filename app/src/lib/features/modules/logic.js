/**
 * The Modules page's plain logic: the ROS names, what the modules node's state message means for the page,
 * and which modules "Launch all" / "Stop all" act on. No Svelte, no ROS: tests import it directly.
 */

export const FEATURE_ID = 'modules';

export const NAMES = Object.freeze({
  state: { topic: '/cell/modules/state', type: 'cell_msgs/ModuleStates' },
  launch: { service: '/cell/modules/launch', type: 'cell_msgs/ModuleCommand' },
  stop: { service: '/cell/modules/stop', type: 'cell_msgs/ModuleCommand' },
  output: { service: '/cell/modules/output', type: 'cell_msgs/ModuleOutput' },
});

/** The state topic is published about once a second: older than this, it is stale. */
export const STATE_PERIOD_MS = 3000;
export const OUTPUT_LINES = 60;

/** @typedef {'active' | 'inactive' | 'transitioning' | 'incomplete' | 'unknown'} ModuleStateName */

/** Colour (tone) and label of each state: the label is always shown, never colour alone. */
export const STATE_VIEW = Object.freeze({
  active: { tone: 'ok', label: 'Active' },
  inactive: { tone: 'neutral', label: 'Inactive' },
  transitioning: { tone: 'warn', label: 'Transitioning' },
  incomplete: { tone: 'danger', label: 'Incomplete' },
  unknown: { tone: 'neutral', label: 'Unknown' },
});

/**
 * @typedef {object} ModuleView
 * @property {string} name
 * @property {ModuleStateName} state
 * @property {{ name: string, alive: boolean }[]} nodes
 * @property {boolean} launchable  has launch files: Launch/Stop apply
 * @property {string} target  while transitioning: 'active' (launching) or 'inactive' (stopping)
 * @property {string} message
 */

/** @param {any} s @returns {ModuleStateName} */
function stateName(s) {
  return s === 'active' || s === 'inactive' || s === 'transitioning' || s === 'incomplete' ? s : 'unknown';
}

/**
 * The modules the role sees (the cell file's list from /api/config, in its order), with their live state from the
 * node's message. A module the message does not mention is 'unknown' (the node has not reported it yet).
 * @param {{ name: string }[] | undefined} visible  /api/config features.modules.modules
 * @param {any} msg  cell_msgs/ModuleStates, or null before the first message
 * @returns {ModuleView[]}
 */
export function moduleViews(visible, msg) {
  /** @type {Map<string, any>} */
  const byName = new Map();
  for (const m of Array.isArray(msg?.modules) ? msg.modules : []) if (m && typeof m.name === 'string') byName.set(m.name, m);
  return (visible ?? []).map(({ name }) => {
    const m = byName.get(name);
    const nodes = Array.isArray(m?.nodes) ? m.nodes.map((/** @type {string} */ n, /** @type {number} */ i) => ({ name: String(n), alive: !!m.alive?.[i] })) : [];
    return {
      name,
      state: m ? stateName(m.state) : 'unknown',
      nodes,
      launchable: !!m?.launchable,
      target: typeof m?.target === 'string' ? m.target : '',
      message: typeof m?.message === 'string' ? m.message : '',
    };
  });
}

/** What the state badge says while transitioning: launching or stopping. @param {ModuleView} m */
export function stateLabel(m) {
  if (m.state === 'transitioning') return m.target === 'inactive' ? 'Stopping…' : 'Launching…';
  return STATE_VIEW[m.state].label;
}

/**
 * May this module be launched / stopped now? Never while it settles (transitioning) or when it has no launch files.
 * @param {ModuleView} m
 * @param {'launch' | 'stop'} action
 * @returns {{ ok: boolean, reason: string }}
 */
export function moduleAction(m, action) {
  if (!m.launchable) return { ok: false, reason: 'Monitored only: not started from here' };
  if (m.state === 'transitioning') return { ok: false, reason: 'Wait until it settles' };
  if (m.state === 'unknown') return { ok: false, reason: 'State not known yet' };
  if (action === 'launch' && m.state === 'active') return { ok: false, reason: 'Already running' };
  if (action === 'stop' && m.state === 'inactive') return { ok: false, reason: 'Not running' };
  return { ok: true, reason: '' };
}

/**
 * The modules "Launch all" / "Stop all" act on: those the single action would act on now.
 * @param {ModuleView[]} modules @param {'launch' | 'stop'} action
 */
export function bulkTargets(modules, action) {
  return modules.filter((m) => moduleAction(m, action).ok);
}

/** "2 of 3 active", for the page head and Home. @param {ModuleView[]} modules */
export function summary(modules) {
  const counts = { active: 0, inactive: 0, transitioning: 0, incomplete: 0, unknown: 0 };
  for (const m of modules) counts[m.state]++;
  return { ...counts, total: modules.length };
}
