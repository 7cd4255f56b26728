// Recorder (the flight recorder): the recorder node keeps the last seconds of the cell's topics and saves them
// around every error alarm as an MCAP file in $DATA_DIR/recordings. Node: /cell/recorder/. So far the cell-file
// section and the node; the recordings' page (list, download, timeline) is still to come (issue 30).
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'recorder',
  title: 'Recordings',
  schema: featureSchema('recorder'),
});
