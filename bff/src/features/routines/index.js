// Routines (feature 8): record poses and tool actions, save, list, rename, run and delete taught routines.
// Node: /cell/routines/. Running moves the robot (lease); stopping never waits for it.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'routines',
  title: 'Routines',
  schema: featureSchema('routines'),
  // No `groups`: every motion group of the driver (as the routines node offers them); no `tools`: none.
  view: (section, _role, cell) => ({
    groups: section.groups ?? (cell.manual?.groups ?? []).map((/** @type {{ name: string }} */ g) => g.name),
    tools: section.tools || [],
  }),
  // The page shows the arm's live pose while teaching (the driver's state) beside the routines node's own names.
  reads: () => ({
    subscribe: ['/cell/routines/log', '/cell/routines/state', '/cell/manual/state'],
    call_service: ['/cell/routines/list', '/cell/manual/groups'],
  }),
  commands: () => ({
    call_service: ['/cell/routines/record', '/cell/routines/save', '/cell/routines/rename', '/cell/routines/delete'],
  }),
  motion: () => ({ call_service: ['/cell/routines/run'] }),
  stop: () => ({ call_service: ['/cell/routines/stop'] }),
});
