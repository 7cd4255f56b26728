// Malformed requests of every kind get a specific 4xx with a clear message, never a 5xx: multipart bodies with
// unexpected parts, wrong content types, bodies too large or nested deep, bad percent-encoding and odd names in the
// path, undeclared methods. (The schemathesis run in schemathesis.test.js looks for more of the same.)
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { startBff, login, tempDir } from '../helpers.js';
import { httpError, multipartError } from '../../src/core/http/errors.js';

let t;
let cookie;
before(async () => {
  const usb = tempDir('usb-root-');
  fs.mkdirSync(path.join(usb, 'STICK', 'export'), { recursive: true });
  fs.writeFileSync(path.join(usb, 'STICK', 'parts.csv'), 'id,name\n1,from the stick\n');
  t = await startBff({ USB_ROOTS: usb });
  ({ cookie } = await login(t.base, 'admin', t.passwords.admin));
});
after(() => t.stop());

/**
 * A raw request: the path goes out exactly as written (no URL normalisation), any headers and body.
 * @param {string} method @param {string} urlPath
 * @param {{headers?: Record<string, string|number>, body?: string|Buffer, auth?: boolean}} [o]
 * @returns {Promise<{status: number, headers: http.IncomingHttpHeaders, text: string, data: any}>}
 */
function raw(method, urlPath, { headers = {}, body, auth = true } = {}) {
  const { port } = new URL(t.base);
  return new Promise((resolve, reject) => {
    const h = { ...(auth ? { cookie } : {}), ...headers };
    if (body !== undefined && h['content-length'] === undefined && h['transfer-encoding'] === undefined) h['content-length'] = Buffer.byteLength(body);
    const rq = http.request({ host: '127.0.0.1', port, method, path: urlPath, headers: h }, (res) => {
      const chunks = [];
      res.on('data', (c) => chunks.push(c));
      res.on('end', () => {
        const text = Buffer.concat(chunks).toString();
        let data = null;
        try { data = JSON.parse(text); } catch { /* not JSON */ }
        resolve({ status: res.statusCode, headers: res.headers, text, data });
      });
    });
    rq.on('error', reject);
    if (body !== undefined) rq.write(body);
    rq.end();
  });
}

/** Assert a status and an error message (JSON {error}) matching re. */
function expectError(r, status, re, what = '') {
  assert.equal(r.status, status, `${what} -> ${r.status} ${r.text}`);
  assert.equal(typeof r.data?.error, 'string', `${what}: a JSON error`);
  assert.match(r.data.error, re, what);
}

/** A multipart body from parts [{name, filename?, content}]. */
function multipart(parts, boundary = 'XyZbOuNdArY') {
  const body = parts.map((p) => `--${boundary}\r\nContent-Disposition: form-data; name="${p.name}"${p.filename ? `; filename="${p.filename}"` : ''}\r\n` +
    `${p.filename ? 'Content-Type: application/octet-stream\r\n' : ''}\r\n${p.content}\r\n`).join('') + `--${boundary}--\r\n`;
  return { body, headers: { 'content-type': `multipart/form-data; boundary=${boundary}` } };
}
const CSV = 'id,name\n1,uploaded\n';
const upload = (m, name = 'parts.csv') => raw('POST', `/api/database/files/${name}/upload`, m);

test('multipart: unexpected file fields, too many fields or files, no boundary, truncated: 400 with what was wrong', async () => {
  expectError(await upload(multipart([{ name: 'other', filename: 'a.csv', content: CSV }])), 400, /unexpected file field \("other"\).*field "file"/, 'file in an unknown field');
  expectError(await upload(multipart([{ name: 'file', filename: 'a.csv', content: CSV }, { name: 'file', filename: 'b.csv', content: CSV }])), 400, /only one file/, 'two files');
  const fields = Array.from({ length: 8 }, (_, i) => ({ name: `f${i}`, content: 'x' }));
  expectError(await upload(multipart([...fields, { name: 'file', filename: 'a.csv', content: CSV }])), 400, /too many (form fields|parts)/, 'many extra fields');
  expectError(await upload(multipart([{ name: '', content: 'x' }, { name: 'file', filename: 'a.csv', content: CSV }])), 400, /no field name/, 'a part without a name');
  expectError(await upload({ body: 'xx', headers: { 'content-type': 'multipart/form-data' } }), 400, /malformed multipart body/, 'no boundary');
  const cut = multipart([{ name: 'file', filename: 'a.csv', content: CSV }]);
  expectError(await upload({ ...cut, body: cut.body.slice(0, -20) }), 400, /malformed multipart body/, 'truncated body');
  expectError(await upload(multipart([{ name: 'file', content: CSV }])), 400, /no file in field "file"/, 'a text field named file');
  // A few extra text fields beside the file are ignored; odd unicode in their names too.
  const ok = await upload(multipart([{ name: 'note', content: 'hi' }, { name: 'n\u00e4me\u{1F600}', content: '\u0000' }, { name: 'file', filename: 'a.csv', content: CSV }]));
  assert.equal(ok.status, 200, ok.text);
  assert.equal(fs.readFileSync(path.join(t.dataDir, 'database', 'parts.csv'), 'utf8'), CSV);
});

test('too large: an upload over the limit, a JSON body over 64 kB: 413', async () => {
  const big = 'x'.repeat(11 * 1024 * 1024);
  expectError(await upload(multipart([{ name: 'file', filename: 'a.csv', content: big }])), 413, /larger than the limit/, 'declared length');
  // Without a Content-Length (chunked), the limit is enforced while receiving.
  const m = multipart([{ name: 'file', filename: 'a.csv', content: big }]);
  expectError(await upload({ body: m.body, headers: { ...m.headers, 'transfer-encoding': 'chunked' } }), 413, /larger than the limit/, 'chunked');
  const json = JSON.stringify({ username: 'admin', password: 'p'.repeat(70 * 1024) });
  expectError(await raw('POST', '/api/auth/login', { body: json, headers: { 'content-type': 'application/json' } }), 413, /larger than the limit of 65536 bytes/, 'JSON');
});

test('content types: not JSON where JSON is expected, not multipart for an upload, unknown charset or encoding: 415', async () => {
  const login = (headers, body = '{"username":"a","password":"b"}') => raw('POST', '/api/auth/login', { headers, body, auth: false });
  expectError(await login({ 'content-type': 'text/plain' }), 415, /expected application\/json/, 'text/plain');
  expectError(await login({}), 415, /expected application\/json/, 'no content type');
  expectError(await login({ 'content-type': 'application/json; charset=koi8-r' }), 415, /unsupported charset "koi8-r"/, 'charset');
  expectError(await login({ 'content-type': 'application/json', 'content-encoding': 'zstd-x' }), 415, /unsupported content encoding "zstd-x"/, 'encoding');
  expectError(await upload({ body: '{}', headers: { 'content-type': 'application/json' } }), 415, /multipart\/form-data/, 'upload as JSON');
  const restore = await raw('POST', '/api/database/files/parts.csv/restore', { body: 'backup=x', headers: { 'content-type': 'application/x-www-form-urlencoded' } });
  expectError(restore, 415, /expected application\/json/, 'restore as a form');
  expectError(await upload(multipart([{ name: 'file', filename: 'a.png', content: CSV }])), 415, /needs a \.csv file, not \.png/, 'wrong extension');
});

test('JSON: malformed, deeply nested, wrong shapes: 400; a GET body is ignored', async () => {
  const post = (p, body) => raw('POST', p, { body, headers: { 'content-type': 'application/json' } });
  expectError(await post('/api/auth/login', '{"username":'), 400, /malformed JSON body/, 'malformed');
  expectError(await post('/api/auth/login', '['.repeat(30000) + ']'.repeat(30000)), 400, /invalid request body: must be object/, 'deep arrays');
  expectError(await post('/api/control/take', '{"force":' + '{"a":'.repeat(10000) + '1' + '}'.repeat(10001)), 400, /invalid request body at \/force: must be boolean/, 'deep objects');
  expectError(await post('/api/database/files/parts.csv/restore', '"just a string"'), 400, /malformed JSON body/, 'a bare string (strict JSON)');
  expectError(await post('/api/database/files/parts.csv/restore', '{"backup":"../../users.json"}'), 400, /\/backup: does not have the required form/, 'backup with ../');
  expectError(await post('/api/database/files/parts.csv/from-drive', '{"drive":"0:STICK","path":"a/../../x.csv"}'), 400, /\/path: does not have the required form/, 'path with ..');
  expectError(await post('/api/database/files/parts.csv/from-drive', '{"drive":"0:STICK/..","path":"parts.csv"}'), 400, /\/drive: does not have the required form/, 'drive with /');
  const g = await raw('GET', '/api/auth/me', { body: '{"not json', headers: { 'content-type': 'application/json' } });
  assert.equal(g.status, 200, g.text);
});

test('path parameters: bad percent-encoding, NUL, odd unicode, very long names: 400 or 404, never 500', async () => {
  const long = 'a'.repeat(300);
  const cases = [
    ['GET', '/api/database/files/%E0%A4%A/backups', 400, /malformed percent-encoding/],
    ['GET', '/api/database/files/%FF/backups', 400, /malformed percent-encoding/],
    ['GET', '/api/database/drives/%E0%A4%A/files', 400, /malformed percent-encoding/],
    ['POST', '/api/database/files/%C0%AF/restore', 400, /malformed percent-encoding/],
    ['GET', '/api/database/files/%00/backups', 400, /invalid file name/],
    ['GET', '/api/database/files/parts.csv%00/backups', 400, /invalid file name/],
    ['GET', `/api/database/files/${long}.csv/backups`, 400, /invalid file name/],
    ['GET', `/api/database/files/${encodeURIComponent('p\u00e4rts.csv')}/backups`, 400, /invalid file name/],
    ['GET', `/api/database/files/${encodeURIComponent('\u{1F600}\u202E.csv')}/backups`, 400, /invalid file name/],
    ['GET', '/api/database/files/nothere.csv/backups', 404, /not a database file/],
    ['GET', `/api/database/drives/${encodeURIComponent('\u{1F600}')}/files`, 400, /invalid drive id/],
    ['GET', `/api/database/drives/0:${long}/files`, 400, /invalid drive id/],
    ['GET', `/api/database/drives/0:${encodeURIComponent('\u00e9\u00e9')}/files`, 404, /no drive/],
    ['GET', '/api/database/drives/0:STICK%2F..%2F../files', 400, /invalid drive id/],
    ['GET', `/api/database/drives/0:STICK/files?path=${long}`, 404, /no such file on the drive/],
    ['GET', `/api/database/drives/0:STICK/files?path=${long}/${long}`, 404, /no such file on the drive/],
    ['GET', '/api/database/drives/0:STICK/files?path=%E0%A4%A', 404, /no such file on the drive/],
    ['GET', '/api/database/drives/0:STICK/files?path=%00', 400, /invalid path/],
    ['GET', '/api/database/files//backups', 404, /no such API/],
  ];
  for (const [method, p, status, re] of cases) {
    const body = method === 'POST' ? '{"backup":"x.y"}' : undefined;
    expectError(await raw(method, p, { body, headers: body ? { 'content-type': 'application/json' } : {} }), status, re, `${method} ${p.slice(0, 80)}`);
  }
  const ok = await raw('GET', '/api/database/drives/0:STICK/files');
  assert.equal(ok.status, 200, ok.text);
  assert.deepEqual(ok.data.entries.map((e) => e.name), ['export', 'parts.csv']);
});

test('user-ish strings: odd unicode user names and passwords are a plain 401', async () => {
  for (const username of ['\u0000', '\u{1F600}'.repeat(16), '__proto__', 'constructor', 'admin\u202E', 'a'.repeat(64)]) {
    const r = await raw('POST', '/api/auth/login', { auth: false, body: JSON.stringify({ username, password: '\uD800x' }), headers: { 'content-type': 'application/json' } });
    if (r.status === 429) break; // the throttle may stop us first: also a declared answer
    expectError(r, 401, /Invalid user name or password/, JSON.stringify(username));
  }
  const q = await raw('GET', `/api/audit?user=${encodeURIComponent('\u{1F600}\u0000')}&since=%E0%A4%A&limit=-1&offset=abc`);
  assert.equal(q.status, 200, q.text);
});

test('routing: undeclared methods on documented paths are 405 with Allow, OPTIONS 204; other variants never 500', async () => {
  let r = await raw('DELETE', '/api/health');
  expectError(r, 405, /DELETE is not allowed/, 'DELETE health');
  assert.equal(r.headers.allow, 'GET, HEAD, OPTIONS');
  r = await raw('GET', '/api/auth/login');
  expectError(r, 405, /GET is not allowed/, 'GET login');
  assert.equal(r.headers.allow, 'POST, OPTIONS');
  r = await raw('PUT', '/api/database/files/whatever/restore');
  assert.equal(r.status, 405);
  assert.equal(r.headers.allow, 'POST, OPTIONS');
  r = await raw('TRACE', '/api/control/heartbeat', { auth: false });
  assert.equal(r.status, 405);
  r = await raw('OPTIONS', '/api/database/files/parts.csv/upload');
  assert.equal(r.status, 204);
  assert.equal(r.headers.allow, 'POST, OPTIONS');
  expectError(await raw('TRACE', '/api/nothing'), 404, /no such API/, 'unknown path');
  // Express matches routes case-insensitively and with a trailing slash: validation must match the same way.
  expectError(await raw('POST', '/api/auth/login/', { auth: false }), 415, /expected application\/json/, 'trailing slash');
  expectError(await raw('POST', '/API/Auth/Login', { auth: false, body: '{}', headers: { 'content-type': 'application/json' } }), 400, /required property 'username'/, 'other case');
  // HEAD is answered by the GET route.
  assert.equal((await raw('HEAD', '/api/health')).status, 200);
});

test('httpError maps client errors to their 4xx and everything else to 500', () => {
  assert.deepEqual(httpError(new URIError('URI malformed')), { status: 400, message: 'malformed percent-encoding in the URL', clientError: true });
  assert.equal(httpError(Object.assign(new Error('x'), { status: 413, type: 'entity.too.large', limit: 10 })).message, 'request body larger than the limit of 10 bytes');
  assert.equal(httpError(Object.assign(new Error('nope'), { status: 404 })).status, 404);
  assert.deepEqual(httpError(Object.assign(new Error('secret detail'), { status: 999 })), { status: 500, message: 'internal error', clientError: false });
  assert.equal(httpError(Object.assign(new Error('hidden'), { status: 400, expose: false })).status, 500);
  assert.equal(httpError(new TypeError('boom')).status, 500);
  assert.equal(httpError(null).status, 500);
  assert.deepEqual(multipartError(Object.assign(new Error('Unexpected field'), { name: 'MulterError', code: 'LIMIT_UNEXPECTED_FILE', field: 'x' })),
    { status: 400, message: 'unexpected file field ("x")', clientError: true });
  assert.equal(multipartError(Object.assign(new Error('File too large'), { name: 'MulterError', code: 'LIMIT_FILE_SIZE' })).status, 413);
  assert.equal(multipartError(new Error('Unexpected end of form')).status, 400);
  assert.equal(multipartError(Object.assign(new Error('ENOSPC'), { code: 'ENOSPC', syscall: 'write' })).status, 500, 'a full disk is ours');
});

test('a body refused by validation is audited like any refusal: who, which route, why', async () => {
  const post = (p, body, type = 'application/json') => raw('POST', p, { body, headers: { 'content-type': type } });
  const auditLines = () => fs.readFileSync(path.join(t.dataDir, 'audit.log'), 'utf8').trim().split('\n').map((l) => JSON.parse(l));
  const before = auditLines().length;
  expectError(await post('/api/control/take', '{"force":"yes"}'), 400, /\/force: must be boolean/, 'a wrong type');
  expectError(await post('/api/database/files/parts.csv/restore', 'backup=x', 'application/x-www-form-urlencoded'), 415, /expected application\/json/, 'a form');
  const added = auditLines().slice(before).filter((e) => e.op === 'request.invalid');
  assert.equal(added.length, 2, JSON.stringify(auditLines().slice(before)));
  assert.deepEqual(added.map((e) => [e.user, e.role, e.target, e.outcome]), [
    ['admin', 'admin', 'POST /api/control/take', 'denied'],
    ['admin', 'admin', 'POST /api/database/files/{name}/restore', 'denied'],
  ]);
  assert.match(added[0].detail, /^400: invalid request body at \/force: must be boolean/);
  assert.match(added[1].detail, /^415: expected application\/json/);
});
