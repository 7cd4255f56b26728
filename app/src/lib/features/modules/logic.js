/**
 * The Modules page's plain logic: the ROS names, what the modules node's state message means for the page,
 * and which modules "Launch all" / "Stop all" act on. No Svelte, no ROS: tests import it directly. Texts come from
 * messages/modules.
 */
import { m } from '$lib/paraglide/messages.js';

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

/** Colour (tone) and label (in the user's language) of each state: the label is always shown, never colour alone. */
export const STATE_VIEW = Object.freeze({
  active: { tone: 'ok', get label() { return m.modules_state_active(); } },
  inactive: { tone: 'neutral', get label() { return m.modules_state_inactive(); } },
  transitioning: { tone: 'warn', get label() { return m.modules_state_transitioning(); } },
  incomplete: { tone: 'danger', get label() { return m.modules_state_incomplete(); } },
  unknown: { tone: 'neutral', get label() { return m.modules_state_unknown(); } },
});

/**
 * @typedef {object} ModuleView
 * @property {string} name
 * @property {string | Record<string, string>} title  what the page calls it (the cell file's title, else the name)
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
 * @param {{ name: string, title?: string | Record<string, string> }[] | undefined} visible  /api/config features.modules.modules
 * @param {any} msg  cell_msgs/ModuleStates, or null before the first message
 * @returns {ModuleView[]}
 */
export function moduleViews(visible, msg) {
  /** @type {Map<string, any>} */
  const byName = new Map();
  for (const x of Array.isArray(msg?.modules) ? msg.modules : []) if (x && typeof x.name === 'string') byName.set(x.name, x);
  return (visible ?? []).map(({ name, title }) => {
    const x = byName.get(name);
    const nodes = Array.isArray(x?.nodes) ? x.nodes.map((/** @type {string} */ n, /** @type {number} */ i) => ({ name: String(n), alive: !!x.alive?.[i] })) : [];
    return {
      name,
      title: title ?? name,
      state: x ? stateName(x.state) : 'unknown',
      nodes,
      launchable: !!x?.launchable,
      target: typeof x?.target === 'string' ? x.target : '',
      message: typeof x?.message === 'string' ? x.message : '',
    };
  });
}

/** What the state badge says while transitioning: launching or stopping. @param {ModuleView} mod */
export function stateLabel(mod) {
  if (mod.state === 'transitioning') return mod.target === 'inactive' ? m.modules_stopping() : m.modules_launching();
  return STATE_VIEW[mod.state].label;
}

/**
 * May this module be launched / stopped now? Never while it settles (transitioning) or when it has no launch files.
 * @param {ModuleView} mod
 * @param {'launch' | 'stop'} action
 * @returns {{ ok: boolean, reason: string }}
 */
export function moduleAction(mod, action) {
  if (!mod.launchable) return { ok: false, reason: m.modules_reason_monitored() };
  if (mod.state === 'transitioning') return { ok: false, reason: m.modules_reason_settling() };
  if (mod.state === 'unknown') return { ok: false, reason: m.modules_reason_unknown() };
  if (action === 'launch' && mod.state === 'active') return { ok: false, reason: m.modules_reason_running() };
  if (action === 'stop' && mod.state === 'inactive') return { ok: false, reason: m.modules_reason_not_running() };
  return { ok: true, reason: '' };
}

/**
 * The modules "Launch all" / "Stop all" act on: those the single action would act on now.
 * @param {ModuleView[]} modules @param {'launch' | 'stop'} action
 */
export function bulkTargets(modules, action) {
  return modules.filter((mod) => moduleAction(mod, action).ok);
}

/** "2 of 3 active", for the page head and Home. @param {ModuleView[]} modules */
export function summary(modules) {
  const counts = { active: 0, inactive: 0, transitioning: 0, incomplete: 0, unknown: 0 };
  for (const mod of modules) counts[mod.state]++;
  return { ...counts, total: modules.length };
}
