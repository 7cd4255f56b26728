// Throttling, audit, lease, sliding sessions and the users-file guard, through the real HTTP app.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { startBff, login, tempDir } from '../helpers.js';
import { LoginThrottle } from '../../src/core/auth/throttle.js';
import { ControlLease } from '../../src/core/control/lease.js';
import { AuditLog } from '../../src/core/audit/audit-log.js';
import { readEnv, REPO_ROOT } from '../../src/core/config/env.js';
import { createBff, StartupError } from '../../src/app.js';

let t;
before(async () => { t = await startBff(); });
after(async () => { await t.stop(); });

const post = (p, cookie, body) => fetch(`${t.base}${p}`, {
  method: 'POST', headers: { 'content-type': 'application/json', ...(cookie ? { cookie } : {}) }, body: body === undefined ? undefined : JSON.stringify(body),
});

test('throttle: 5 failures lock a key for the cool-down, whoever asks', () => {
  let now = 0;
  const th = new LoginThrottle({ max: 5, windowMs: 1000, cooldownMs: 3000, now: () => now });
  for (let i = 0; i < 4; i++) th.fail(['user:a']);
  assert.equal(th.retryAfter(['user:a']), 0);
  th.fail(['user:a']);
  assert.equal(th.retryAfter(['user:a', 'ip:x']), 3);
  now = 3001;
  assert.equal(th.retryAfter(['user:a']), 0);
  for (let i = 0; i < 4; i++) { th.fail(['user:b']); now += 600; }
  th.fail(['user:b']);
  assert.equal(th.retryAfter(['user:b']), 0, 'failures outside the window do not count');
});

test('login throttling over HTTP: 429 after 5 failures, the same for unknown users, audited', async () => {
  for (const who of ['operator', 'ghost']) {
    // A BFF of its own per user name, so the address's own counter does not decide the outcome.
    const s = await startBff();
    try {
      for (let i = 0; i < 5; i++) assert.equal((await login(s.base, who, 'bad-password')).res.status, 401);
      const r = await login(s.base, who, who === 'operator' ? s.passwords.operator : 'x');
      assert.equal(r.res.status, 429, `${who} is throttled even with the right password`);
      assert.ok(Number(r.res.headers.get('retry-after')) > 0);
      assert.equal(r.setCookie, '');
      assert.equal((await login(s.base, 'admin', s.passwords.admin)).res.status, 429, 'the address is throttled too');
      const denied = s.bff.audit.query({ op: 'login', outcome: 'denied' });
      assert.equal(denied.total, 7);
      assert.ok(denied.entries.some((e) => e.detail === 'throttled' && e.user === who));
    } finally {
      await s.stop();
    }
  }
});

test('the audit API is admin-only, pages, and filters', async () => {
  await login(t.base, 'admin', 'wrong-once');
  await login(t.base, 'admin', t.passwords.admin);
  const { cookie } = await login(t.base, 'admin', t.passwords.admin);
  const all = await (await fetch(`${t.base}/api/audit?limit=2`, { headers: { cookie } })).json();
  assert.equal(all.entries.length, 2);
  assert.ok(all.total > 2);
  const logins = await (await fetch(`${t.base}/api/audit?op=login&outcome=ok`, { headers: { cookie } })).json();
  assert.ok(logins.entries.every((e) => e.op === 'login' && e.outcome === 'ok'));
  assert.ok(logins.entries.some((e) => e.user === 'admin' && e.ip));
  const page2 = await (await fetch(`${t.base}/api/audit?limit=1&offset=1`, { headers: { cookie } })).json();
  assert.deepEqual(page2.entries[0], all.entries[1]);
  await t.bff.users.add('opx', 'operator', 'opx-password');
  const op = await login(t.base, 'opx', 'opx-password');
  assert.equal((await fetch(`${t.base}/api/audit`, { headers: { cookie: op.cookie } })).status, 403);
});

test('audit log rotates by size and queries across the rotated files', () => {
  const log = new AuditLog({ dir: tempDir(), maxBytes: 400, keep: 3 });
  for (let i = 0; i < 20; i++) log.record({ user: 'u', role: 'r', ip: null, op: 'x', target: String(i), outcome: 'ok' });
  assert.ok(fs.existsSync(`${log.file}.1`));
  assert.ok(!fs.existsSync(`${log.file}.4`));
  const q = log.query({ limit: 100 });
  assert.equal(q.entries[0].target, '19', 'newest first');
  assert.ok(q.total < 20, 'the oldest were rotated away');
});

test('lease: one holder, heartbeats, expiry, admin take-over, release', () => {
  let now = 0;
  const events = [];
  const lease = new ControlLease({ timeoutMs: 2000, now: () => now, onChange: (e) => events.push(e) });
  const a = { username: 'op1', role: 'operator', sid: 'a' };
  const b = { username: 'op2', role: 'operator', sid: 'b' };
  const admin = { username: 'boss', role: 'admin', sid: 'c' };
  assert.ok(lease.take(a).ok);
  const refused = lease.take(b);
  assert.equal(refused.ok, false);
  assert.match(refused.reason, /held by op1/);
  assert.equal(lease.take(b, { force: true }).ok, false, 'only roles the cell file lets take over');
  now = 1500; assert.ok(lease.heartbeat(a));
  now = 3000; assert.ok(lease.isHolder(a), 'the heartbeat kept it');
  now = 5100; assert.equal(lease.isHolder(a), false, 'missed heartbeats end it');
  assert.ok(lease.take(b).ok);
  assert.equal(lease.take(admin, { force: true }).ok, false, 'force alone is not enough');
  assert.ok(lease.take(admin, { force: true, mayTakeOver: true }).ok);
  assert.ok(lease.isHolder(admin) && !lease.isHolder(b));
  assert.equal(lease.heartbeat(b), false);
  assert.ok(lease.release(admin));
  assert.equal(lease.describe(), null);
  assert.deepEqual(events, ['taken', 'expired', 'taken', 'taken-over', 'taken', 'released']);
});

test('lease over HTTP: take, conflict with holder named, heartbeat, release on logout', async () => {
  await t.bff.users.add('op-a', 'operator', 'op-a-password');
  await t.bff.users.add('op-b', 'operator', 'op-b-password');
  const a = await login(t.base, 'op-a', 'op-a-password');
  const b = await login(t.base, 'op-b', 'op-b-password');
  const took = await post('/api/control/take', a.cookie);
  assert.equal(took.status, 200);
  assert.equal((await took.json()).you, true);
  const conflict = await post('/api/control/take', b.cookie, { force: true });
  assert.equal(conflict.status, 409);
  assert.equal((await conflict.json()).holder.username, 'op-a');
  assert.equal((await post('/api/control/heartbeat', a.cookie)).status, 200);
  // The demo cell lets admins (take_over: true) take over; a second operator cannot, even with force.
  const boss = await login(t.base, 'admin', t.passwords.admin);
  const over = await post('/api/control/take', boss.cookie, { force: true });
  assert.equal(over.status, 200);
  assert.equal((await over.json()).holder.username, 'admin');
  assert.equal((await post('/api/control/heartbeat', a.cookie)).status, 409, 'op-a lost it');
  await post('/api/control/release', boss.cookie);
  assert.equal((await post('/api/control/take', a.cookie)).status, 200);
  assert.equal((await post('/api/control/heartbeat', b.cookie)).status, 409);
  await post('/api/auth/logout', a.cookie);
  const st = await (await fetch(`${t.base}/api/control`, { headers: { cookie: b.cookie } })).json();
  assert.equal(st.holder, null, 'logout released it');
  assert.equal((await post('/api/control/take', b.cookie, { force: 'yes' })).status, 400, 'validated against the OpenAPI document');
});

test('sliding renewal: a token past half its life is replaced, in the same session', async () => {
  const ttl = 3;
  const s = await startBff({ SESSION_TTL_S: String(ttl) });
  // JWT times are whole seconds: wait for the token's own clock, not a fixed time from the login.
  /** @param {string} cookie */
  const expOf = (cookie) => JSON.parse(Buffer.from(cookie.split('=')[1].split('.')[1], 'base64url').toString()).exp;
  /** @param {number} epochS */
  const until = (epochS) => new Promise((r) => setTimeout(r, Math.max(0, epochS * 1000 - Date.now())));
  try {
    const { cookie } = await login(s.base, 'admin', s.passwords.admin);
    const exp = expOf(cookie);
    await until(exp - ttl / 2 + 0.05); // the token must really age past half its life
    const r = await fetch(`${s.base}/api/auth/me`, { headers: { cookie } });
    assert.equal(r.status, 200);
    const renewed = (r.headers.get('set-cookie') || '').split(';')[0];
    assert.match(renewed, /^cell_session=/);
    assert.notEqual(renewed, cookie);
    assert.ok(expOf(renewed) > exp, 'the renewed token lives longer');
    await until(exp + 0.05);
    assert.equal((await fetch(`${s.base}/api/auth/me`, { headers: { cookie } })).status, 401, 'the old token expired');
    assert.equal((await fetch(`${s.base}/api/auth/me`, { headers: { cookie: renewed } })).status, 200, 'the renewed one lives on');
  } finally {
    await s.stop();
  }
});

test('a group- or world-writable users file stops the start', async () => {
  const dir = tempDir();
  const file = path.join(dir, 'users.json');
  fs.writeFileSync(file, JSON.stringify({ version: 1, users: [] }), { mode: 0o666 });
  fs.chmodSync(file, 0o666);
  await assert.rejects(createBff(readEnv({ DATA_DIR: dir }), { log: () => {} }), (e) => e instanceof StartupError && /chmod 600/.test(e.message));
});

test('security headers: CSP without unsafe-inline scripts, frame-ancestors none', async () => {
  const r = await fetch(`${t.base}/`);
  const csp = r.headers.get('content-security-policy');
  assert.match(csp, /default-src 'self'/);
  assert.match(csp, /frame-ancestors 'none'/);
  assert.doesNotMatch(csp.match(/script-src[^;]*/)[0], /unsafe-inline/);
  assert.equal(r.headers.get('referrer-policy'), 'no-referrer');
});

test('a role none of whose commands moves the robot may not take control (the twin cell\'s maintenance)', async () => {
  const s = await startBff({ CELL_CONFIG: path.join(REPO_ROOT, 'config/twin-arm-cell.yaml') });
  try {
    const maint = await login(s.base, 'maintenance', s.passwords.maintenance);
    const refused = await fetch(`${s.base}/api/control/take`, { method: 'POST', headers: { cookie: maint.cookie, 'content-type': 'application/json' }, body: '{}' });
    assert.equal(refused.status, 403);
    assert.match((await refused.json()).error, /no command that moves the robot/);
    const op = await login(s.base, 'operator', s.passwords.operator);
    assert.equal((await fetch(`${s.base}/api/control/take`, { method: 'POST', headers: { cookie: op.cookie } })).status, 200, 'the operator runs the process');
  } finally {
    await s.stop();
  }
});
