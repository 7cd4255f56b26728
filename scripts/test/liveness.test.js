// The supervisor's hang check (scripts/supervise/liveness.js), on a fake clock.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { Liveness, DEFAULT_GRACE_MS, graceFromEnv } from '../supervise/liveness.js';

function clock(t = 1_000_000) {
  const c = { t, now: () => c.t, advance: (ms) => { c.t += ms; } };
  return c;
}

test('a process that has not answered since it started is starting, not hung, however long it takes', () => {
  const c = clock();
  const l = new Liveness({ graceMs: 30_000, now: c.now });
  l.started();
  c.advance(120_000);
  assert.equal(l.hung(), false);
  assert.equal(l.silentMs(), 0);
});

test('once it answered, the grace period without an answer makes it hung; an answer in time resets it', () => {
  const c = clock();
  const l = new Liveness({ graceMs: 30_000, now: c.now });
  l.started();
  l.answered();
  c.advance(29_999);
  assert.equal(l.hung(), false);
  l.answered();
  c.advance(29_999);
  assert.equal(l.hung(), false);
  c.advance(1);
  assert.equal(l.hung(), true);
  assert.equal(l.silentMs(), 30_000);
});

test('a restarted process is judged afresh: not hung until it has answered again', () => {
  const c = clock();
  const l = new Liveness({ graceMs: 1000, now: c.now });
  l.answered();
  c.advance(5000);
  assert.equal(l.hung(), true);
  l.started();
  assert.equal(l.hung(), false);
  c.advance(5000);
  assert.equal(l.hung(), false);
});

test('LIVENESS_TIMEOUT_S: 30 s by default, 0 turns the check off, anything else not a number of seconds is an error', () => {
  assert.equal(graceFromEnv({}), DEFAULT_GRACE_MS);
  assert.equal(DEFAULT_GRACE_MS, 30_000);
  assert.equal(graceFromEnv({ LIVENESS_TIMEOUT_S: '' }), DEFAULT_GRACE_MS);
  assert.equal(graceFromEnv({ LIVENESS_TIMEOUT_S: '2.5' }), 2500);
  assert.equal(graceFromEnv({ LIVENESS_TIMEOUT_S: '0' }), null);
  assert.throws(() => graceFromEnv({ LIVENESS_TIMEOUT_S: 'soon' }), /LIVENESS_TIMEOUT_S must be a number of seconds/);
  assert.throws(() => graceFromEnv({ LIVENESS_TIMEOUT_S: '-1' }), /LIVENESS_TIMEOUT_S/);
});
