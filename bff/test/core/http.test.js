import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startBff, login } from '../helpers.js';
import { buildOpenApi, expressPath } from '../../src/core/http/openapi.js';
import { FEATURES } from '../../src/features/index.js';

const openapi = buildOpenApi(FEATURES);

let t;
before(async () => { t = await startBff(); });
after(async () => { await t.stop(); });

const get = (p, cookie) => fetch(`${t.base}${p}`, { headers: cookie ? { cookie } : {} });

test('health answers without a session and says ROS is not reachable here', async () => {
  const r = await get('/api/health');
  assert.equal(r.status, 200);
  const body = await r.json();
  assert.equal(body.status, 'ok');
  assert.deepEqual(body.ros, { master: false, rosbridge: false });
});

test('wrong password: 401, no cookie; unknown user: the same answer', async () => {
  const a = await login(t.base, 'admin', 'not-the-password');
  assert.equal(a.res.status, 401);
  assert.equal(a.setCookie, '');
  const b = await login(t.base, 'nobody', 'not-the-password');
  assert.equal(b.res.status, 401);
  assert.deepEqual(await a.res.json(), await b.res.json());
});

test('malformed and invalid login bodies get clear 400s', async () => {
  const post = (body, type = 'application/json') => fetch(`${t.base}/api/auth/login`, { method: 'POST', headers: { 'content-type': type }, body });
  let r = await post('{"username":');
  assert.equal(r.status, 400);
  assert.match((await r.json()).error, /malformed JSON/);
  r = await post(JSON.stringify({ username: 'admin' }));
  assert.equal(r.status, 400);
  assert.match((await r.json()).error, /password/);
  r = await post('username=admin', 'application/x-www-form-urlencoded');
  assert.equal(r.status, 415);
});

test('login sets an HttpOnly SameSite=Strict cookie; me and config follow the role', async () => {
  const { res, cookie, setCookie } = await login(t.base, 'operator', t.passwords.operator);
  assert.equal(res.status, 200);
  assert.deepEqual(await res.json(), { username: 'operator', role: 'operator' });
  assert.match(setCookie, /HttpOnly/);
  assert.match(setCookie, /SameSite=Strict/);
  assert.deepEqual(await (await get('/api/auth/me', cookie)).json(), { username: 'operator', role: 'operator' });
  const cfg = await (await get('/api/config', cookie)).json();
  assert.deepEqual(cfg.pages.map((p) => p.id), ['home', 'modules', 'process', 'manual', 'scene', 'sensors', 'video', 'alarms', 'recorder']);
  assert.equal(cfg.operation_mode.type, 'cell_msgs/OperationMode');
  // The role's modules, with the cell file's title per language when it has one.
  assert.deepEqual(cfg.features.modules.modules, [{ name: 'Diagnostics', title: { en: 'Diagnostics', es: 'Diagnóstico', fi: 'Diagnostiikka', de: 'Diagnose' }, roles: ['admin', 'operator'] }]);
});

test('without a session: me, config and system are 401', async () => {
  for (const p of ['/api/auth/me', '/api/config', '/api/system']) assert.equal((await get(p)).status, 401, p);
});

test('system page API: admin gets users and roles, operator gets 403', async () => {
  const op = await login(t.base, 'operator', t.passwords.operator);
  assert.equal((await get('/api/system', op.cookie)).status, 403);
  const ad = await login(t.base, 'admin', t.passwords.admin);
  const r = await get('/api/system', ad.cookie);
  assert.equal(r.status, 200);
  const body = await r.json();
  assert.deepEqual(body.users, [{ username: 'admin', role: 'admin' }, { username: 'operator', role: 'operator' }]);
  assert.ok(body.cell_file.endsWith('demo-cell.yaml'));
  assert.ok(!JSON.stringify(body).includes('scrypt'), 'no hashes leave the BFF');
});

test('logout revokes the token at once', async () => {
  const { cookie } = await login(t.base, 'admin', t.passwords.admin);
  assert.equal((await get('/api/auth/me', cookie)).status, 200);
  const out = await fetch(`${t.base}/api/auth/logout`, { method: 'POST', headers: { cookie } });
  assert.equal(out.status, 204);
  assert.match(out.headers.get('set-cookie'), /Max-Age=0/);
  assert.equal((await get('/api/auth/me', cookie)).status, 401);
});

test('a removed user loses the session; a cross-origin POST is refused', async () => {
  await t.bff.users.add('dave', 'operator', 'password-dave');
  const { cookie } = await login(t.base, 'dave', 'password-dave');
  assert.equal((await get('/api/auth/me', cookie)).status, 200);
  t.bff.users.remove('dave');
  assert.equal((await get('/api/auth/me', cookie)).status, 401);
  const r = await fetch(`${t.base}/api/auth/login`, {
    method: 'POST', headers: { 'content-type': 'application/json', origin: 'http://evil.example' },
    body: JSON.stringify({ username: 'admin', password: t.passwords.admin }),
  });
  assert.equal(r.status, 403);
});

test('static: hashed assets immutable, shell and service worker no-cache, SPA fallback, API 404 stays JSON', async () => {
  const a = await get('/_app/immutable/entry.abc123.js');
  assert.match(a.headers.get('cache-control'), /immutable/);
  assert.equal((await get('/sw.js')).headers.get('cache-control'), 'no-cache');
  const deep = await get('/system');
  assert.equal(deep.status, 200);
  assert.equal(deep.headers.get('cache-control'), 'no-cache');
  assert.match(await deep.text(), /shell/);
  const api = await get('/api/nothing');
  assert.equal(api.status, 404);
  assert.match((await api.json()).error, /no such API/);
  assert.equal(a.headers.get('x-content-type-options'), 'nosniff');
});

test('every API route of the app is in the OpenAPI document, and the document is served', async () => {
  const served = await (await get('/api/openapi.json')).json();
  assert.equal(served.openapi, '3.1.0');
  const documented = new Set(Object.entries(openapi.paths).flatMap(([p, ops]) => Object.keys(ops).map((m) => `${m.toUpperCase()} ${expressPath(p)}`)));
  const routes = [];
  const walk = (stack) => {
    for (const layer of stack) {
      if (layer.route) for (const m of Object.keys(layer.route.methods)) routes.push(`${m.toUpperCase()} ${layer.route.path}`);
      else if (layer.handle?.stack) walk(layer.handle.stack);
    }
  };
  walk(t.bff.app.router.stack);
  const api = routes.filter((r) => r.split(' ')[1].startsWith('/api/'));
  assert.ok(api.length >= 7, `found routes: ${api}`);
  for (const r of api) assert.ok(documented.has(r), `${r} is not in the OpenAPI document`);
});

test('the document declares what the core answers around each operation, and the rules the code enforces', async () => {
  const { FILE_NAME, DRIVE_ID, BACKUP_NAME, REL_PATH, REL_PATH_OR_ROOT } = await import('../../src/features/database/database-files.js');
  const featurePaths = new Set(FEATURES.flatMap((f) => Object.keys(f.openapi || {})));
  for (const [p, ops] of Object.entries(openapi.paths)) {
    for (const [method, op] of Object.entries(ops)) {
      const has = (s) => assert.ok(op.responses[s]?.description, `${method.toUpperCase()} ${p} declares ${s}`);
      has(405);
      assert.ok(op.responses[431], `${p}: 431 (Node's header size limit)`);
      assert.ok(op.responses[405].headers.Allow, `${p}: 405 names the Allow header`);
      const secured = op.security.length > 0 && op.security.every((s) => Object.keys(s).length > 0);
      if (secured) has(401);
      if (secured && featurePaths.has(p)) has(403);
      if (method !== 'get') for (const s of [400, 403, 413, 415]) has(s);
      if ((op.parameters || []).length) has(400);
    }
  }
  const loginOp = openapi.paths['/api/auth/login'].post;
  assert.ok(loginOp.responses[415] && loginOp.responses[429].headers['Retry-After']);
  assert.equal(openapi.paths['/api/auth/logout'].post.responses[401], undefined, 'logout works without a session');
  const db = openapi.paths;
  assert.equal(db['/api/database/files/{name}/backups'].get.parameters[0].schema.pattern, FILE_NAME.pattern);
  assert.equal(db['/api/database/files/{name}/backups'].get.parameters[0].schema.maxLength, FILE_NAME.maxLength);
  const listing = db['/api/database/drives/{drive}/files'].get.parameters;
  assert.equal(listing[0].schema.pattern, DRIVE_ID.pattern);
  assert.equal(listing[1].schema.pattern, REL_PATH_OR_ROOT.pattern);
  const fromDrive = db['/api/database/files/{name}/from-drive'].post.requestBody.content['application/json'].schema.properties;
  assert.equal(fromDrive.drive.pattern, DRIVE_ID.pattern);
  assert.equal(fromDrive.path.pattern, REL_PATH.pattern);
  assert.equal(db['/api/database/files/{name}/restore'].post.requestBody.content['application/json'].schema.properties.backup.pattern, BACKUP_NAME.pattern);
});
