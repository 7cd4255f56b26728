// The user's language is kept with the account; the BFF's client errors carry a stable code for the app to translate.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { LOCALES, UserStore, UsersError } from '../../src/core/auth/users.js';
import { startBff, login, tempDir } from '../helpers.js';

test("the BFF's languages are the app's", () => {
  const settings = JSON.parse(fs.readFileSync(new URL('../../../app/project.inlang/settings.json', import.meta.url), 'utf8'));
  assert.deepEqual([...LOCALES].sort(), [...settings.locales].sort());
});

test('the store keeps a language per user, refuses others, and forgets it on null', async () => {
  const store = new UserStore(path.join(tempDir(), 'users.json'));
  await store.add('ana', 'operator', 'longenough');
  assert.deepEqual(store.setLocale('ana', 'es'), { username: 'ana', role: 'operator', locale: 'es' });
  assert.deepEqual(await new UserStore(store.file).authenticate('ana', 'longenough'), { username: 'ana', role: 'operator', locale: 'es' });
  assert.throws(() => store.setLocale('ana', 'xx'), UsersError);
  assert.throws(() => store.setLocale('nobody', 'fi'), /no user/);
  store.setLocale('ana', null);
  assert.deepEqual(store.profile('ana'), { username: 'ana', role: 'operator' });
});

test('PUT /api/auth/me/preferences keeps the language: a new login and /me on another session see it', async () => {
  const a = await startBff();
  try {
    const { cookie } = await login(a.base, 'operator', a.passwords.operator);
    const put = (body, c = cookie) => fetch(`${a.base}/api/auth/me/preferences`, { method: 'PUT', headers: { cookie: c, 'content-type': 'application/json' }, body: JSON.stringify(body) });
    let res = await put({ locale: 'fi' });
    assert.equal(res.status, 200);
    assert.deepEqual(await res.json(), { username: 'operator', role: 'operator', locale: 'fi' });

    const again = await login(a.base, 'operator', a.passwords.operator);
    assert.deepEqual(await again.res.json(), { username: 'operator', role: 'operator', locale: 'fi' });
    const me = await fetch(`${a.base}/api/auth/me`, { headers: { cookie: again.cookie } });
    assert.equal((await me.json()).locale, 'fi');
    // Another user is not affected.
    const other = await login(a.base, 'admin', a.passwords.admin);
    assert.equal((await other.res.json()).locale, undefined);

    res = await put({ locale: 'klingon' });
    assert.equal(res.status, 400);
    const bad = await res.json();
    assert.equal(bad.code, 'request.invalid');
    assert.match(bad.error, /locale/);
    res = await put({ locale: null });
    assert.equal(res.status, 200);
    assert.equal((await res.json()).locale, undefined);
    res = await put({ locale: 'de' }, 'cell_session=forged');
    assert.equal(res.status, 401);
    assert.equal((await res.json()).code, 'auth.not_logged_in');
    const audit = fs.readFileSync(path.join(a.dataDir, 'audit.log'), 'utf8');
    assert.match(audit, /"op":"preferences"[^\n]*"detail":"fi"/);
  } finally {
    await a.stop();
  }
});

test('client errors carry a stable code and its values (wrong password, throttled, malformed JSON)', async () => {
  const a = await startBff();
  try {
    const wrong = await login(a.base, 'operator', 'not the password');
    assert.equal(wrong.res.status, 401);
    assert.deepEqual(await wrong.res.json(), { error: 'Invalid user name or password', code: 'auth.invalid_credentials' });
    let res;
    for (let i = 0; i < 20; i++) {
      res = (await login(a.base, 'operator', 'not the password')).res;
      if (res.status === 429) break;
    }
    assert.equal(res.status, 429);
    const throttled = await res.json();
    assert.equal(throttled.code, 'auth.throttled');
    assert.equal(throttled.params.seconds, Number(res.headers.get('retry-after')));

    const { cookie } = await login(a.base, 'admin', a.passwords.admin);
    res = await fetch(`${a.base}/api/control/take`, { method: 'POST', headers: { cookie, 'content-type': 'application/json' }, body: '{"x":' });
    assert.equal(res.status, 400);
    assert.equal((await res.json()).code, 'request.malformed_json');
  } finally {
    await a.stop();
  }
});
