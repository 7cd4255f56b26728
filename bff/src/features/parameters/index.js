// Parameters (feature 7): typed cell parameters in the CSV the parameters node owns. Node: /cell/parameters/.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'parameters',
  title: 'Parameters',
  schema: featureSchema('parameters'),
  // The CSV's path stays on the robot PC: the page gets the definitions, the node the values.
  view: (section) => ({ items: section.items }),
  reads: () => ({ call_service: ['/cell/parameters/get'], subscribe: ['/cell/parameters/values'] }),
  commands: () => ({ call_service: ['/cell/parameters/set'] }),
});
