// Modules (feature 2): launch and stop groups of launch files, and watch their state. Node: /cell/modules/.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'modules',
  title: 'Modules',
  schema: featureSchema('modules'),
  // A role sees the modules it may launch (no `roles` on a module: every role that sees the page).
  view: (section, role) => ({ modules: section.filter((m) => !m.roles || m.roles.includes(role)).map(({ name, roles }) => ({ name, roles })) }),
  check: (section, cell) => section.flatMap((m, i) => (m.roles || []).flatMap((r, j) => (
    cell.roles[r] ? [] : [`modules[${i}].roles[${j}]: unknown role "${r}"`]))),
  reads: () => ({ subscribe: ['/cell/modules/state'], call_service: ['/cell/modules/output'] }),
  commands: () => ({ call_service: ['/cell/modules/launch', '/cell/modules/stop'] }),
});
