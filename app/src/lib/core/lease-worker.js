// The control lease's heartbeat, off the page's main thread (lease-beat.js says why). Messages from the page:
// {start: BeatOptions, gen}, {stop: true}, {ack: true}; to the page: {gen, answer: RawAnswer}.
import { HeartbeatLoop } from './lease-beat.js';
import { fetchJson } from './fetch-json.js';

/** @type {HeartbeatLoop<import('./fetch-json.js').RawAnswer>} */
const loop = new HeartbeatLoop({ send: (timeoutMs) => fetchJson('POST', '/api/control/heartbeat', undefined, undefined, timeoutMs) });

self.onmessage = (/** @type {MessageEvent} */ e) => {
  const m = e.data ?? {};
  if (m.start) {
    const gen = m.gen;
    loop.start(m.start, (answer) => self.postMessage({ gen, answer }));
  } else if (m.stop) loop.stop();
  else if (m.ack) loop.ack();
};
