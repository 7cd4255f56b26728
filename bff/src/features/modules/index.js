// Modules (feature 2): launch and stop groups of launch files, and watch their state. Node: /cell/modules/.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

const LAUNCH = '/cell/modules/launch';
const STOP = '/cell/modules/stop';

export default defineFeature({
  id: 'modules',
  title: 'Modules',
  schema: featureSchema('modules'),
  // A role sees the modules it may launch (no `roles` on a module: every role that sees the page).
  view: (section, role) => ({ modules: section.filter((m) => !m.roles || m.roles.includes(role)).map(({ name, title, roles }) => ({ name, ...(title ? { title } : {}), roles })) }),
  check: (section, cell) => section.flatMap((m, i) => (m.roles || []).flatMap((r, j) => (
    cell.roles[r] ? [] : [`modules[${i}].roles[${j}]: unknown role "${r}"`]))),
  reads: () => ({ subscribe: ['/cell/modules/state'], call_service: ['/cell/modules/output'] }),
  commands: () => ({ call_service: [LAUNCH, STOP] }),
  // The grants let a role call launch/stop at all; which modules it may launch is per module (`roles`).
  checkArgs: (section, role, op, target, msg) => {
    if (op !== 'call_service' || (target !== LAUNCH && target !== STOP)) return null;
    const name = msg?.args?.name;
    const m = section.find((x) => x.name === name);
    if (!m) return `no module named ${JSON.stringify(String(name ?? ''))} in this cell`;
    return !m.roles || m.roles.includes(role) ? null : `the ${role} role may not launch or stop the module "${m.name}"`;
  },
});
