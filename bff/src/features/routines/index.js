// Routines (feature 8): record, save, list, run and delete taught routines. Node: /cell/routines/. Running moves the robot.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'routines',
  title: 'Routines',
  schema: featureSchema('routines'),
  view: (section) => ({ groups: section.groups, tools: section.tools || [] }),
  reads: () => ({ subscribe: ['/cell/routines/log'], call_service: ['/cell/routines/list'] }),
  commands: () => ({ call_service: ['/cell/routines/record', '/cell/routines/save', '/cell/routines/delete'] }),
  motion: () => ({ call_service: ['/cell/routines/run'] }),
});
