// Video (feature 6): the cell's camera streams; only the shown one is subscribed.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'video',
  title: 'Cameras',
  schema: featureSchema('video'),
  view: (section) => ({ streams: (section.streams || []).map(({ name, topic }) => ({ name, topic })) }),
  reads: (section) => ({ subscribe: (section.streams || []).map((s) => s.topic) }),
});
