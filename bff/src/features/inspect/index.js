// Inspect (the commissioning engineer's tools, issue 26): so far the ROS log. The inspect node keeps the recent
// /rosout_agg and answers /cell/inspect/log with it, filtered; the page shows that history, then the live log.
// Read-only: a role that sees the page reads the log; nothing here changes the cell.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'inspect',
  title: 'Inspect',
  schema: featureSchema('inspect'),
  view: (section) => ({ log_keep_entries: section.log_keep_entries ?? 5000, log_keep_s: section.log_keep_s ?? 600 }),
  reads: () => ({ subscribe: ['/rosout_agg'], call_service: ['/cell/inspect/log'] }),
});
