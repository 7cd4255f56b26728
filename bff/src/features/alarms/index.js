// Alarms (feature 9): the cell's safety state and alarm list, reset from the UI. Node: /cell/alarms/.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'alarms',
  title: 'Alarms',
  schema: featureSchema('alarms'),
  view: (section) => section,
  reads: () => ({ subscribe: ['/cell/alarms/list', '/cell/alarms/status'] }),
  commands: () => ({ call_service: ['/cell/alarms/reset'] }),
});
