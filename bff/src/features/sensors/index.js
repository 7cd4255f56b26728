// Sensors (feature 3): Chart.js graphs of the topics the cell file lists.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'sensors',
  title: 'Sensors',
  schema: featureSchema('sensors'),
  view: (section) => ({ graphs: section }),
  reads: (section) => ({ subscribe: section.map((g) => g.topic) }),
});
