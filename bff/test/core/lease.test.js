// The control lease across a restart of the BFF: kept when the BFF is back within the heartbeat timeout of the
// holder's last heartbeat, ended (and the holder told why) after it.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { startBff, login, tempDir } from '../helpers.js';
import { ControlLease } from '../../src/core/control/lease.js';
import { LeaseFile } from '../../src/core/control/lease-file.js';
import { AwakeClock } from '../../src/core/control/awake-clock.js';

const op = { username: 'op1', role: 'operator', sid: 'a' };

test('lease: every change is persisted; a new lease resumes within the timeout, lapses after it', () => {
  let now = 1000;
  /** @type {any[]} */
  const saved = [];
  const events = [];
  const first = new ControlLease({ timeoutMs: 2000, now: () => now, persist: (s) => saved.push(s), onChange: (e) => events.push(e) });
  assert.ok(first.take(op).ok);
  now = 1500;
  assert.ok(first.heartbeat(op));
  assert.deepEqual(saved.at(-1), { ...op, since: 1000, beat: 1500 }, 'the heartbeat is saved');

  now = 4900; // started 1.9 s after the last heartbeat (3400), ready 1.5 s later
  const back = new ControlLease({ timeoutMs: 2000, now: () => now, onChange: (e) => events.push(e) });
  assert.equal(back.resume(saved.at(-1), 3400), 'resumed');
  assert.ok(back.isHolder(op));
  assert.deepEqual(back.describe(), { username: 'op1', role: 'operator', since: new Date(1000).toISOString(), resumed_at: new Date(4900).toISOString() });
  now = 7000; // the rest of the start-up took 2.1 s more
  back.listening();
  assert.equal(back.describe()?.resumed_at, new Date(7000).toISOString());
  now = 8900;
  assert.ok(back.heartbeat(op), 'a full timeout from listening for the next heartbeat');

  now = 3501; // started 2.001 s after the last heartbeat
  const late = new ControlLease({ timeoutMs: 2000, now: () => now, persist: (s) => saved.push(s), onChange: (e) => events.push(e) });
  assert.equal(late.resume({ ...op, since: 1000, beat: 1500 }), 'lapsed');
  assert.equal(late.isHolder(op), false);
  assert.equal(saved.at(-1), null, 'the lapsed lease is cleared on disk');
  assert.equal(late.heartbeat(op), false);
  assert.match(/** @type {string} */ (late.endedFor(op)), /lapsed while the server restarted .*2\.0 s after the last heartbeat; the limit is 2 s/);
  assert.equal(late.endedFor({ sid: 'b' }), null, 'only the last holder is told');
  assert.deepEqual(events, ['taken', 'resumed', 'lapsed-in-restart']);
  assert.equal(new ControlLease().resume(null), 'none');
});

test('lease: the reason a holder lost control is kept for it (expiry, take-over, release)', () => {
  let now = 0;
  const lease = new ControlLease({ timeoutMs: 2000, now: () => now });
  const boss = { username: 'boss', role: 'admin', sid: 'c' };
  lease.take(op);
  now = 2001;
  assert.equal(lease.heartbeat(op), false);
  assert.match(/** @type {string} */ (lease.endedFor(op)), /expired/);
  lease.take(op);
  lease.take(boss, { force: true, mayTakeOver: true });
  assert.equal(lease.endedFor(op), 'taken over by boss (admin)');
  lease.release(boss, 'released-on-disconnect');
  assert.match(/** @type {string} */ (lease.endedFor(boss)), /last live connection closed/);
});

test('lease file: round trip, a missing file, a torn or foreign file is ignored with a message', () => {
  const dir = tempDir();
  const logs = [];
  const f = new LeaseFile(path.join(dir, 'control-lease.json'), (m) => logs.push(m));
  assert.equal(f.read(), null);
  f.write({ ...op, since: 1, beat: 2 });
  assert.deepEqual(f.read(), { ...op, since: 1, beat: 2 });
  f.write(null);
  assert.equal(f.read(), null);
  for (const bad of ['{"username": "op1", "ro', '[1,2]', '{"username":"op1","role":"operator","sid":"a","since":"x","beat":2}']) {
    fs.writeFileSync(f.file, bad);
    assert.equal(f.read(), null);
  }
  assert.equal(logs.length, 3);
  assert.match(logs[0], /not a saved lease; starting with no holder/);
});

test('lease over HTTP across a BFF restart: kept when back in time (resumed_at), ended with the reason after', async () => {
  const first = await startBff();
  const DATA_DIR = first.dataDir;
  await first.bff.users.add('op-a', 'operator', 'op-a-password');
  const a = await login(first.base, 'op-a', 'op-a-password');
  const post = (/** @type {string} */ base, /** @type {string} */ p) => fetch(`${base}${p}`, { method: 'POST', headers: { cookie: a.cookie } });
  assert.equal((await post(first.base, '/api/control/take')).status, 200);
  assert.equal((await post(first.base, '/api/control/heartbeat')).status, 200);
  await first.stop();

  const second = await startBff({ DATA_DIR }, { startedAt: Date.now() });
  try {
    const hb = await post(second.base, '/api/control/heartbeat');
    assert.equal(hb.status, 200, 'the holder keeps control after a quick restart');
    const view = await hb.json();
    assert.equal(view.you, true);
    assert.equal(view.holder.username, 'op-a');
    assert.ok(Date.parse(view.holder.resumed_at) > Date.parse(view.holder.since));
  } finally {
    await second.stop();
  }

  // The BFF was started again longer than the timeout (5 s in the demo cell) after the last heartbeat.
  const file = path.join(DATA_DIR, 'control-lease.json');
  const saved = JSON.parse(fs.readFileSync(file, 'utf8'));
  fs.writeFileSync(file, JSON.stringify({ ...saved, beat: Date.now() - 8000 }));
  const third = await startBff({ DATA_DIR }, { startedAt: Date.now() });
  try {
    const hb = await post(third.base, '/api/control/heartbeat');
    assert.equal(hb.status, 409);
    const body = await hb.json();
    assert.equal(body.holder, null);
    assert.match(body.ended, /control lapsed while the server restarted \(it was back 8\.\d s after the last heartbeat; the limit is 5 s\)/);
    const audit = fs.readFileSync(third.bff.audit.file, 'utf8');
    assert.match(audit, /"op":"control\.resumed"/);
    assert.match(audit, /"op":"control\.lapsed-in-restart"/);
  } finally {
    await third.stop();
  }
});

test('awake clock: runs with the process, a stall beyond the step cap is not counted', () => {
  let t = 0;
  const c = new AwakeClock({ now: () => t, timers: false, maxStepMs: 250 });
  for (let i = 0; i < 10; i++) { t += 100; c.tick(); }
  assert.equal(c.now(), 1000);
  t += 3000; // the event loop did not run for 3 s
  assert.equal(c.now(), 1250);
});

test('lease: a BFF stalled past the timeout keeps the holder whose heartbeat was waiting; real silence still ends it', () => {
  let wall = 0;
  const awake = new AwakeClock({ now: () => wall, timers: false });
  const lease = new ControlLease({ timeoutMs: 2000, now: () => wall, awake: () => awake.now() });
  const run = (/** @type {number} */ ms) => { for (let i = 0; i < ms / 100; i++) { wall += 100; awake.tick(); } };
  assert.ok(lease.take(op).ok);
  run(400);
  wall += 2500; // the BFF's event loop was stalled 2.5 s; the heartbeat sent meanwhile is handled first thing after
  assert.ok(lease.heartbeat(op), 'the stall is not the holder\'s silence');
  run(1900);
  assert.ok(lease.isHolder(op));
  run(200); // 2.1 s of the BFF running without a heartbeat
  assert.equal(lease.isHolder(op), false);
  assert.match(/** @type {string} */ (lease.endedFor(op)), /expired/);
});
