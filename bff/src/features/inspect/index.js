// Inspect (the commissioning engineer's tools, issue 26): the ROS log, topics and nodes. The inspect node keeps the
// recent /rosout_agg and answers /cell/inspect/log with it, filtered; /cell/inspect/graph lists topics and nodes;
// /cell/inspect/topic_stats measures a topic's rate and bandwidth while a page asks; /cell/inspect/diagnostics is the
// drivers' /diagnostics with silent statuses marked STALE. Read-only: nothing here changes
// the cell. Reading any topic's last message (/cell/inspect/echo) is its own grant: the roles of `echo_roles`.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

const ECHO = '/cell/inspect/echo';

/** @param {any} section @param {string} role */
const mayEcho = (section, role) => Array.isArray(section?.echo_roles) && section.echo_roles.includes(role);

export default defineFeature({
  id: 'inspect',
  title: 'Inspect',
  schema: featureSchema('inspect'),
  check: (section, cell) => (section.echo_roles || []).flatMap((/** @type {string} */ r, /** @type {number} */ i) => (cell.roles?.[r] ? [] : [`inspect.echo_roles[${i}]: no role ${JSON.stringify(r)} in roles`])),
  view: (section, role) => ({
    log_keep_entries: section.log_keep_entries ?? 5000, log_keep_s: section.log_keep_s ?? 600, can_echo: mayEcho(section, role),
  }),
  reads: () => ({ subscribe: ['/rosout_agg', '/cell/inspect/diagnostics'], call_service: ['/cell/inspect/log', '/cell/inspect/graph', '/cell/inspect/topic_stats', ECHO] }),
  // The page's grant reaches the echo service; only echo_roles may call it (whatever else the role may read).
  checkArgs: (section, role, op, target) => (op === 'call_service' && target === ECHO && !mayEcho(section, role)
    ? `the ${role} role may not read a topic's messages here (the cell file's inspect.echo_roles)` : null),
});
