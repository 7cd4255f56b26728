import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import jwt from 'jsonwebtoken';
import { UserStore, ensureInitialUsers, UsersError } from '../../src/core/auth/users.js';
import { TokenService, RevocationList, loadOrCreateKey } from '../../src/core/auth/tokens.js';
import { tempDir, startBff, login } from '../helpers.js';
import { createBff } from '../../src/app.js';
import { readEnv } from '../../src/core/config/env.js';
import { sessionOf } from '../../src/core/auth/session.js';

test('users file holds scrypt hashes only, and authenticate checks them', async () => {
  const dir = tempDir();
  const store = new UserStore(path.join(dir, 'users.json'));
  await store.add('alice', 'operator', 'correct horse');
  const text = fs.readFileSync(store.file, 'utf8');
  assert.ok(!text.includes('correct horse'));
  assert.match(JSON.parse(text).users[0].hash, /^scrypt\$16384\$8\$1\$/);
  assert.equal(fs.statSync(store.file).mode & 0o777, 0o600);
  assert.deepEqual(await store.authenticate('alice', 'correct horse'), { username: 'alice', role: 'operator' });
  assert.equal(await store.authenticate('alice', 'wrong horse'), null);
  assert.equal(await store.authenticate('mallory', 'correct horse'), null);
  assert.equal(await store.authenticate(undefined, undefined), null);
});

test('add/passwd/remove validate their input', async () => {
  const store = new UserStore(path.join(tempDir(), 'users.json'));
  await assert.rejects(store.add('Bad Name', 'operator', 'longenough'), UsersError);
  await assert.rejects(store.add('bob', 'operator', 'short'), /at least 8/);
  await store.add('bob', 'operator', 'longenough');
  await assert.rejects(store.add('bob', 'admin', 'longenough'), /already exists/);
  await store.passwd('bob', 'newpassword');
  assert.ok(await store.authenticate('bob', 'newpassword'));
  assert.equal(await store.authenticate('bob', 'longenough'), null);
  store.remove('bob');
  assert.throws(() => store.remove('bob'), /no user/);
  assert.deepEqual(store.list(), []);
});

test('a second store sees users added by another process without a restart', async () => {
  const file = path.join(tempDir(), 'users.json');
  const running = new UserStore(file);
  assert.equal(running.get('carol'), null);
  await new UserStore(file).add('carol', 'admin', 'password1');
  assert.equal(running.get('carol')?.role, 'admin');
});

test('first start creates admin and operator with random passwords in a 0600 file, once', async () => {
  const dir = tempDir();
  const store = new UserStore(path.join(dir, 'users.json'));
  const first = await ensureInitialUsers(store, dir, ['admin', 'operator']);
  assert.deepEqual(first.users.map((u) => u.role), ['admin', 'operator']);
  assert.equal(fs.statSync(first.file).mode & 0o777, 0o600);
  const text = fs.readFileSync(first.file, 'utf8');
  for (const u of first.users) {
    assert.ok(text.includes(u.password));
    assert.ok(await store.authenticate(u.username, u.password));
  }
  assert.notEqual(first.users[0].password, first.users[1].password);
  assert.equal(await ensureInitialUsers(store, dir, ['admin', 'operator']), null);
});

test('tokens: valid ones pass; forged, expired, alg:none, wrong-key and revoked ones do not', () => {
  const dir = tempDir();
  const key = loadOrCreateKey(dir);
  assert.equal(fs.statSync(path.join(dir, 'session.key')).mode & 0o777, 0o600);
  assert.deepEqual(loadOrCreateKey(dir), key, 'the key is generated once');
  const svc = new TokenService({ key, ttlS: 60, revoked: new RevocationList(path.join(dir, 'revoked.json')) });
  const good = svc.issue({ username: 'alice', role: 'operator' });
  const claims = svc.verify(good);
  assert.equal(claims.sub, 'alice');
  assert.equal(claims.role, 'operator');

  const [h, p] = good.split('.');
  const forgedPayload = Buffer.from(JSON.stringify({ ...claims, role: 'admin' })).toString('base64url');
  assert.equal(svc.verify(`${h}.${forgedPayload}.${good.split('.')[2]}`), null, 'tampered payload');
  const none = `${Buffer.from('{"alg":"none","typ":"JWT"}').toString('base64url')}.${p}.`;
  assert.equal(svc.verify(none), null, 'alg none');
  const wellFormed = { role: 'admin', sid: 's1', jti: 'x' };
  assert.ok(svc.verify(jwt.sign(wellFormed, key, { subject: 'alice' })), 'control: a well-formed token with our key passes');
  assert.equal(svc.verify(jwt.sign(wellFormed, 'other-key', { subject: 'alice' })), null, 'wrong key');
  const expired = jwt.sign({ ...wellFormed, exp: Math.floor(Date.now() / 1000) - 10 }, key, { subject: 'alice' });
  assert.equal(svc.verify(expired), null, 'expired');
  assert.equal(svc.verify(jwt.sign(wellFormed, key, { subject: 'alice', algorithm: 'HS512' })), null, 'other algorithm');
  const noneAlg = jwt.sign(wellFormed, null, { subject: 'alice', algorithm: 'none' });
  assert.equal(svc.verify(noneAlg), null, 'alg none from jsonwebtoken itself');

  const renewed = svc.issue({ username: 'alice', role: 'operator' }, claims.sid);
  assert.equal(svc.verify(renewed).sid, claims.sid, 'renewal keeps the session id');
  svc.revoke(claims);
  assert.equal(svc.verify(good), null, 'revoked');
  assert.equal(svc.verify(renewed), null, 'logout kills every token of the session');
  const again = new TokenService({ key, ttlS: 60, revoked: new RevocationList(path.join(dir, 'revoked.json')) });
  assert.equal(again.verify(good), null, 'revocation survives a restart');
});

test('a BFF restart keeps sessions (same key in DATA_DIR); a new key ends them', async () => {
  const a = await startBff();
  const { cookie } = await login(a.base, 'admin', a.passwords.admin);
  await a.stop();
  const again = await createBff(readEnv({ DATA_DIR: a.dataDir, APP_DIR: a.env.appDir }), { log: () => {} });
  const req = { headers: { cookie } };
  assert.equal(sessionOf(/** @type {any} */ (req), again.tokens, again.users)?.username, 'admin');
  again.close();
  fs.rmSync(path.join(a.dataDir, 'session.key'));
  const rekeyed = await createBff(readEnv({ DATA_DIR: a.dataDir, APP_DIR: a.env.appDir }), { log: () => {} });
  assert.equal(sessionOf(/** @type {any} */ (req), rekeyed.tokens, rekeyed.users), null);
  rekeyed.close();
});
