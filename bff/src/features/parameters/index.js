// Parameters (feature 7): typed cell parameters in the CSV a node owns. Node: /cell/parameters/.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'parameters',
  title: 'Parameters',
  schema: featureSchema('parameters'),
  // The CSV's path stays on the robot PC.
  view: (section) => ({ items: section.items }),
  reads: () => ({ call_service: ['/cell/parameters/get'] }),
  commands: () => ({ call_service: ['/cell/parameters/set'] }),
});
