// The relay's send window against a simulated link (one FIFO at a byte rate, a one-way delay each way, pongs
// back on the uncongested return path), fed 30 Hz x 30 KB frames through a latest-wins lane as the outbox does.
// On an 80 ms round trip without a bandwidth cap a fixed 48 KiB window cannot carry 30 frames a second; the
// adaptive one does. On a 0.5 MB/s link it must not grow into a queue of old frames.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { SendWindow, DEFAULTS } from '../../src/core/ros/outbox.js';

const FRAME = 30 * 1024;
const pct = (/** @type {number[]} */ xs, /** @type {number} */ p) => { const s = [...xs].sort((a, b) => a - b); return s[Math.min(s.length - 1, Math.floor((p / 100) * s.length))]; };

/**
 * @param {{rate: number, delay: number, secs?: number, fixed?: boolean}} link  rate bytes/ms (Infinity: no cap), delay ms each way
 * @returns {{fps: number, ageP95: number, window: number, maxWindow: number}} over the second half
 */
function simulate({ rate, delay, secs = 20, fixed = false }) {
  let t = 0;
  const w = new SendWindow(fixed ? { maxWindowBytes: DEFAULTS.windowBytes } : {}, () => t);
  /** @type {{at: number, kind: 'frame'|'pong'|'produce', produced?: number, ping?: string}[]} */
  const events = [];
  const add = (/** @type {any} */ e) => { let i = events.length; while (i > 0 && events[i - 1].at > e.at) i--; events.splice(i, 0, e); };
  let linkFree = 0;
  /** @type {number | null} the lane: the newest frame not yet written (its production time) */
  let lane = null;
  /** @type {{at: number, age: number}[]} */
  const arrived = [];
  let maxWindow = 0;
  const pump = () => {
    while (lane !== null && w.open()) {
      const produced = lane;
      lane = null;
      const start = Math.max(t, linkFree);
      linkFree = start + (Number.isFinite(rate) ? FRAME / rate : 0);
      add({ at: linkFree + delay, kind: 'frame', produced });
      const ping = w.wrote(FRAME);
      if (ping) add({ at: linkFree + 2 * delay, kind: 'pong', ping });   // the ping follows the frame
    }
  };
  add({ at: 2 * delay, kind: 'pong', ping: w.probe() });   // the relay's probe when the socket opens
  for (let k = 0; k * (1000 / 30) < secs * 1000; k++) add({ at: k * (1000 / 30), kind: 'produce' });
  while (events.length) {
    const e = /** @type {any} */ (events.shift());
    t = e.at;
    if (e.kind === 'produce') lane = t;
    else if (e.kind === 'frame') arrived.push({ at: t, age: t - e.produced });
    else w.pong(e.ping);
    pump();
    if (t > (secs * 1000) / 2) maxWindow = Math.max(maxWindow, w.windowBytes);
  }
  const late = arrived.filter((a) => a.at > (secs * 1000) / 2);
  return { fps: late.length / (secs / 2), ageP95: pct(late.map((a) => a.age), 95), window: w.windowBytes, maxWindow };
}

test('an 80 ms round trip without a cap: a fixed 48 KiB window carries fewer than 27 frames a second, the adaptive one all 30', () => {
  const fixed = simulate({ rate: Infinity, delay: 40, fixed: true });
  const adaptive = simulate({ rate: Infinity, delay: 40 });
  assert.ok(fixed.fps < 27, `fixed window: ${fixed.fps} fps`);
  assert.ok(adaptive.fps >= 29.5, `adaptive window: ${adaptive.fps} fps`);
  assert.ok(adaptive.ageP95 < 150, `age p95 ${adaptive.ageP95} ms`);
  assert.ok(adaptive.window < 8 * FRAME, `the window grows to what the stream needs, not without bound: ${adaptive.window}`);
});

test('a 0.5 MB/s link: the window stays near its least, frames arrive as fresh as with the fixed window', () => {
  const fixed = simulate({ rate: 500, delay: 2, fixed: true });
  const adaptive = simulate({ rate: 500, delay: 2 });
  assert.ok(adaptive.maxWindow <= 2.5 * FRAME, `window ${adaptive.maxWindow}`);
  assert.ok(adaptive.ageP95 <= fixed.ageP95 * 1.3, `age p95 ${adaptive.ageP95} ms, fixed ${fixed.ageP95} ms`);
  assert.ok(adaptive.fps >= fixed.fps * 0.9, `${adaptive.fps} fps, fixed ${fixed.fps}`);
});

test('a fast local link: the window is not the limit and stays small', () => {
  const r = simulate({ rate: 100_000, delay: 0.1 });
  assert.ok(r.fps >= 29.5 && r.window === DEFAULTS.windowBytes, JSON.stringify(r));
});
