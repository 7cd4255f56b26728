// Video (feature 6): the cell's camera streams; only the shown one is subscribed. A CompressedImage stream is read
// as the camera publishes it; a raw (sensor_msgs/Image) stream only through the video node
// (ros_backend cell_nodes/video): the viewer asks /cell/video/request for a size and reads the JPEG topic it
// names, so no raw frame (80 MB/s at 720p) is ever granted to a browser.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

/** @param {{type?: string}} s */
export const isRaw = (s) => s.type === 'raw';

export default defineFeature({
  id: 'video',
  title: 'Cameras',
  schema: featureSchema('video'),
  view: (section) => ({
    streams: (section.streams || []).map(({ name, topic, type }) => ({ name, topic, type: type === 'raw' ? 'raw' : 'compressed' })),
  }),
  check: (section) =>
    (section.streams || []).flatMap((/** @type {{sim_size?: number[], type?: string}} */ s, /** @type {number} */ i) =>
      s.sim_size && !isRaw(s) ? [`video.streams[${i}].sim_size: only a raw stream has a size of its own (the sim's CompressedImage cameras use its camera size)`] : []),
  reads: (section) => {
    const streams = section.streams || [];
    const raw = streams.some(isRaw);
    return {
      subscribe: [
        ...streams.filter((s) => !isRaw(s)).map((s) => s.topic),
        ...(raw ? ['/cell/video/*/*', '/cell/video/status'] : []),
      ],
      call_service: raw ? ['/cell/video/request'] : [],
    };
  },
});
