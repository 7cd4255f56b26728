// Routines (feature 8): record poses and tool actions, save, list, rename, run and delete taught routines.
// Node: /cell/routines/. Running moves the robot (lease); stopping never waits for it.
import { defineFeature, featureSchema } from '../../core/features/feature.js';
import { groupNames, stateTopic } from '../manual/index.js';

/** The groups routines record for: the section's, else every group of the driver. @param {any} section @param {any} cell */
const groupsOf = (section, cell) => (Array.isArray(section?.groups) ? section.groups : groupNames(cell?.manual));

/**
 * The group of each of the section's tools (manual.tools[].group; default the first group), so the page offers
 * only the chosen group's tools.
 * @param {any} section @param {any} cell @returns {Record<string, string>}
 */
function toolGroups(section, cell) {
  const first = groupNames(cell?.manual)[0] ?? '';
  const tools = Array.isArray(cell?.manual?.tools) ? cell.manual.tools : [];
  /** @type {Record<string, string>} */
  const out = {};
  for (const name of section?.tools || []) {
    const t = tools.find((/** @type {any} */ x) => x?.name === name);
    out[name] = typeof t?.group === 'string' && t.group ? t.group : first;
  }
  return out;
}

/**
 * The cell file's titles of the section's tools' actions (manual.tools[].actions[].title), by "tool/action", so the
 * page names an action as the Manual page's button does.
 * @param {any} section @param {any} cell @returns {Record<string, unknown>}
 */
function actionTitles(section, cell) {
  const tools = Array.isArray(cell?.manual?.tools) ? cell.manual.tools : [];
  /** @type {Record<string, unknown>} */
  const out = {};
  for (const name of section?.tools || []) {
    const t = tools.find((/** @type {any} */ x) => x?.name === name);
    for (const a of Array.isArray(t?.actions) ? t.actions : []) if (a?.title) out[`${name}/${a.name}`] = a.title;
  }
  return out;
}

export default defineFeature({
  id: 'routines',
  title: 'Routines',
  schema: featureSchema('routines'),
  // No `groups`: every motion group of the driver (as the routines node offers them); no `tools`: none.
  view: (section, _role, cell) => ({
    groups: groupsOf(section, cell),
    tools: section.tools || [],
    tool_groups: toolGroups(section, cell),
    action_titles: actionTitles(section, cell),
  }),
  // The page shows the chosen group's live pose while teaching (its driver state) beside the routines node's names.
  reads: (section, cell) => ({
    subscribe: ['/cell/routines/log', '/cell/routines/state', ...groupsOf(section, cell).map(stateTopic)],
    call_service: ['/cell/routines/list', '/cell/manual/groups'],
  }),
  commands: () => ({
    call_service: ['/cell/routines/record', '/cell/routines/save', '/cell/routines/rename', '/cell/routines/delete'],
  }),
  motion: () => ({ call_service: ['/cell/routines/run'] }),
  stop: () => ({ call_service: ['/cell/routines/stop'] }),
});
