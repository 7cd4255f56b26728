// The supervisor's restart policy (scripts/supervise/restart-policy.js), on a fake clock.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { RestartPolicy, DEFAULTS, restartDelay, seconds } from '../supervise/restart-policy.js';

function clock(t = 1_000_000) {
  const c = { t, now: () => c.t, advance: (ms) => { c.t += ms; } };
  return c;
}

/** Start, run for `ranMs`, crash: returns the decision. */
function runAndCrash(p, c, ranMs) {
  p.started();
  c.advance(ranMs);
  return p.crashed();
}

test('defaults: at once, then 0.5 s doubling to 10 s, reset after 30 s stable, 5 crashes in 60 s', () => {
  assert.deepEqual({ ...DEFAULTS }, { minDelayMs: 500, maxDelayMs: 10_000, stableMs: 30_000, maxCrashes: 5, windowMs: 60_000 });
});

test('the back-off doubles from the minimum up to the cap', () => {
  const c = clock();
  // A large window and crash limit: only the delays matter here.
  const p = new RestartPolicy({ now: c.now, maxCrashes: 100, windowMs: 1000 });
  const delays = [];
  for (let i = 0; i < 8; i++) {
    const d = runAndCrash(p, c, 100);
    assert.equal(d.giveUp, false);
    delays.push(d.delayMs);
    c.advance(d.delayMs);
  }
  assert.deepEqual(delays, [0, 500, 1000, 2000, 4000, 8000, 10_000, 10_000]);
});

test('a child that ran stably starts over with an immediate restart', () => {
  const c = clock();
  const p = new RestartPolicy({ now: c.now });
  assert.equal(runAndCrash(p, c, 1000).delayMs, 0);
  assert.equal(runAndCrash(p, c, 1000).delayMs, 500);
  c.advance(500);
  assert.equal(runAndCrash(p, c, 29_999).delayMs, 1000, 'not quite stable');
  c.advance(1000);
  const d = runAndCrash(p, c, 30_000);
  assert.equal(d.delayMs, 0, 'stable for 30 s');
  assert.equal(d.giveUp, false);
});

test('5 crashes within 60 s are a crash loop: give up on the fifth', () => {
  const c = clock();
  const p = new RestartPolicy({ now: c.now });
  const seen = [];
  for (let i = 1; i <= 5; i++) {
    const d = runAndCrash(p, c, 200);
    seen.push([d.crashes, d.giveUp]);
    c.advance(d.delayMs);
  }
  assert.deepEqual(seen, [[1, false], [2, false], [3, false], [4, false], [5, true]]);
  assert.equal(p.crashed().giveUp, true, 'and stays given up while the window holds them');
});

test('crashes spread wider than the window never give up, however many', () => {
  const c = clock();
  const p = new RestartPolicy({ now: c.now });
  for (let i = 0; i < 50; i++) {
    const d = runAndCrash(p, c, 16_000); // one crash every ~16 s + delay: at most 4 in any 60 s
    assert.equal(d.giveUp, false, `crash ${i + 1}: ${d.crashes} in the window`);
    assert.ok(d.crashes <= 4);
    c.advance(d.delayMs);
  }
});

test('old crashes drop out of the window', () => {
  const c = clock();
  const p = new RestartPolicy({ now: c.now, maxCrashes: 3, windowMs: 10_000 });
  assert.equal(runAndCrash(p, c, 100).crashes, 1);
  assert.equal(runAndCrash(p, c, 100).crashes, 2);
  c.advance(10_000);
  const d = runAndCrash(p, c, 100);
  assert.equal(d.crashes, 1, 'the first two are more than 10 s old');
  assert.equal(d.giveUp, false);
});

test('a crash before any start (e.g. during the first start-up) still counts', () => {
  const c = clock();
  const p = new RestartPolicy({ now: c.now });
  const d = p.crashed();
  assert.deepEqual(d, { giveUp: false, delayMs: 0, crashes: 1, maxCrashes: 5, windowMs: 60_000 });
});

test('options override the defaults, undefined ones do not', () => {
  const p = new RestartPolicy({ minDelayMs: 100, maxDelayMs: undefined, maxCrashes: 3 });
  assert.equal(p.minDelayMs, 100);
  assert.equal(p.maxDelayMs, 10_000);
  assert.equal(p.crashed().delayMs, 0);
  assert.equal(p.crashed().delayMs, 100);
  assert.equal(p.crashed().giveUp, true);
});

test('seconds() and restartDelay() format delays for the log', () => {
  assert.equal(restartDelay(0), 'at once');
  assert.equal(restartDelay(500), 'in 0.5 s');
  assert.equal(seconds(500), '0.5 s');
  assert.equal(seconds(10_000), '10 s');
  assert.equal(seconds(1250), '1.3 s');
});
