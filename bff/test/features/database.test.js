import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import realFsp from 'node:fs/promises';
import http from 'node:http';
import path from 'node:path';
import express from 'express';
import { tempDir } from '../helpers.js';
import { AuditLog } from '../../src/core/audit/audit-log.js';
import { requireSession, requirePage } from '../../src/core/http/guards.js';
import { DatabaseFiles, databaseRoutes, databaseOpenApiPaths, resolveUsbRoots, checkCsv } from '../../src/features/database/index.js';

const OLD_CSV = 'id,name\n1,old part\n';
const NEW_CSV = 'id,name\n1,new part\n2,"quoted, with comma"\n';

/** A cell with a database section, a DATA_DIR with the current files, and a temporary USB root with a drive. */
async function setup({ maxBytes = 4096, fsp } = {}) {
  const dataDir = tempDir();
  const usb = tempDir('usb-root-');
  const outside = tempDir('outside-');
  const cell = {
    pages: [{ id: 'home' }, { id: 'database' }],
    roles: { admin: { pages: ['home', 'database'] }, operator: { pages: ['home'] } },
    database: { directory: 'database', usb_roots: ['/nonexistent-media'], max_upload_bytes: maxBytes, files: ['parts.csv', 'fixtures.yaml', 'recipes.json'] },
  };
  const db = path.join(dataDir, 'database');
  fs.mkdirSync(db);
  fs.writeFileSync(path.join(db, 'parts.csv'), OLD_CSV);
  fs.writeFileSync(path.join(db, 'fixtures.yaml'), 'a: 1\n');
  fs.writeFileSync(path.join(dataDir, 'users.json'), '{"secret": true}');

  const stick = path.join(usb, 'STICK');
  fs.mkdirSync(path.join(stick, 'export'), { recursive: true });
  fs.writeFileSync(path.join(stick, 'parts.csv'), NEW_CSV);
  fs.writeFileSync(path.join(stick, 'export', 'PARTS.CSV'), 'id;name\r\n7;from subdir\r\n');
  fs.writeFileSync(path.join(stick, 'parts.txt'), NEW_CSV);
  fs.writeFileSync(path.join(stick, 'bad.csv'), 'id,name\n1,two,three\n');
  fs.writeFileSync(path.join(stick, 'bad.json'), '{"a": 1,,}');
  fs.writeFileSync(path.join(stick, 'bad.yaml'), 'a: [1, 2\nb: : :\n');
  fs.writeFileSync(path.join(stick, 'fixtures.yaml'), 'fixtures:\n  - id: F1\n');
  fs.writeFileSync(path.join(stick, 'big.csv'), 'a,b\n' + '1,2\n'.repeat(2000));
  fs.writeFileSync(path.join(outside, 'secret.csv'), 'x,y\n1,2\n');
  fs.symlinkSync('/etc/passwd', path.join(stick, 'passwd.csv'));
  fs.symlinkSync(path.join(outside, 'secret.csv'), path.join(stick, 'secret.csv'));
  fs.symlinkSync(outside, path.join(stick, 'outdir'));
  fs.symlinkSync('parts.csv', path.join(stick, 'alias.csv')); // inside the drive: allowed
  fs.writeFileSync(path.join(usb, 'outside-drive.csv'), NEW_CSV); // a file directly in the root, not on a drive

  const audit = new AuditLog({ dir: path.join(dataDir, 'audit') });
  const service = new DatabaseFiles({ cell, dataDir, usbRoots: [usb], audit, fsp });
  const app = express();
  app.set('trust proxy', false);
  app.use('/api', express.json({ limit: '64kb' }));
  app.use((req, res, next) => {
    const u = req.headers['x-test-user'];
    req.session = u ? { username: u, role: u === 'olga' ? 'operator' : 'admin' } : null;
    next();
  });
  app.use(databaseRoutes({ service, guard: [requireSession, requirePage(cell, 'database')], log: () => {} }));
  const server = http.createServer(app);
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  const port = server.address().port;
  const drives = await service.listDrives();
  return {
    dataDir, db, usb, stick, outside, service, audit, port, driveId: drives.find((d) => d.label === 'STICK')?.id,
    async stop() { server.closeAllConnections(); await new Promise((r) => server.close(r)); },
    /** Raw request: the path goes out exactly as written (no client-side ../ normalisation). */
    req(method, urlPath, { json, body, headers = {}, user = 'ada' } = {}) {
      return new Promise((resolve, reject) => {
        const h = { ...headers, ...(user ? { 'x-test-user': user } : {}) };
        let payload = body;
        if (json !== undefined) { payload = JSON.stringify(json); h['content-type'] = 'application/json'; }
        if (payload !== undefined) h['content-length'] = Buffer.byteLength(payload);
        const rq = http.request({ host: '127.0.0.1', port, method, path: urlPath, headers: h }, (res) => {
          let text = '';
          res.on('data', (c) => (text += c));
          res.on('end', () => { let data = null; try { data = JSON.parse(text); } catch { /* not JSON */ } resolve({ status: res.statusCode, data, text }); });
        });
        rq.on('error', reject);
        if (payload !== undefined) rq.write(payload);
        rq.end();
      });
    },
    async upload(name, filename, content, user = 'ada') {
      const fd = new FormData();
      fd.append('file', new Blob([content]), filename);
      const res = await fetch(`http://127.0.0.1:${port}/api/database/files/${name}/upload`, { method: 'POST', body: fd, headers: { 'x-test-user': user } });
      return { status: res.status, data: await res.json() };
    },
  };
}

/** Every file under dir (relative path -> content), to show that nothing changed. */
function snapshot(dir) {
  const out = {};
  const walk = (d) => {
    for (const e of fs.readdirSync(d, { withFileTypes: true })) {
      const p = path.join(d, e.name);
      if (e.isDirectory()) walk(p);
      else out[path.relative(dir, p)] = fs.readFileSync(p, 'utf8');
    }
  };
  walk(dir);
  return out;
}

const entries = (audit, op) => audit.query({ op, limit: 1000 }).entries;

test('lists targets, drives and drive files; symlinks leading outside the drive are not listed', async () => {
  const t = await setup();
  try {
    const files = await t.req('GET', '/api/database/files');
    assert.equal(files.status, 200);
    assert.equal(files.data.max_upload_bytes, 4096);
    assert.deepEqual(files.data.files.map((f) => [f.name, f.exists, f.size]), [['parts.csv', true, OLD_CSV.length], ['fixtures.yaml', true, 5], ['recipes.json', false, null]]);

    const drives = await t.req('GET', '/api/database/drives');
    assert.deepEqual(drives.data.drives.map((d) => d.label), ['STICK']);

    const list = await t.req('GET', `/api/database/drives/${encodeURIComponent(t.driveId)}/files`);
    assert.equal(list.status, 200);
    const names = list.data.entries.map((e) => e.name);
    assert.ok(names.includes('parts.csv') && names.includes('export') && names.includes('alias.csv'));
    for (const n of ['passwd.csv', 'secret.csv', 'outdir']) assert.ok(!names.includes(n), `${n} not listed`);
    assert.deepEqual(list.data.entries.find((e) => e.name === 'parts.csv').targets, ['parts.csv']);
    assert.equal(list.data.entries[0].type, 'dir');

    const sub = await t.req('GET', `/api/database/drives/${encodeURIComponent(t.driveId)}/files?path=export`);
    assert.deepEqual(sub.data.entries.map((e) => e.name), ['PARTS.CSV']);
    const nothere = await t.req('GET', `/api/database/drives/${encodeURIComponent(t.driveId)}/files?path=nothere`);
    assert.equal(nothere.status, 404);
    assert.deepEqual(nothere.data, { error: 'no such file on the drive: nothere', code: 'database.no_such_path', params: { path: 'nothere' } });
    const nope = await t.req('GET', '/api/database/drives/9:NOPE/files');
    assert.equal(nope.status, 404);
    assert.deepEqual(nope.data, { error: 'no drive 9:NOPE', code: 'database.no_drive', params: { drive: '9:NOPE' } });
  } finally {
    await t.stop();
  }
});

test('drive rule: /media/<user>/<drive> layout and USB_ROOTS override', async () => {
  const root = tempDir('media-');
  fs.mkdirSync(path.join(root, 'alice', 'KINGSTON'), { recursive: true });
  fs.writeFileSync(path.join(root, 'alice', 'KINGSTON', 'parts.csv'), NEW_CSV);
  fs.mkdirSync(path.join(root, 'alice', 'EMPTY'));
  fs.mkdirSync(path.join(root, 'usb0'));
  fs.writeFileSync(path.join(root, 'usb0', 'parts.csv'), NEW_CSV);
  fs.mkdirSync(path.join(root, 'bob')); // empty user folder: nothing mounted
  fs.mkdirSync(path.join(root, '.hidden'));
  fs.writeFileSync(path.join(root, '.hidden', 'x.csv'), NEW_CSV);
  const s = new DatabaseFiles({ cell: { database: { directory: 'db', files: ['parts.csv'] } }, dataDir: tempDir(), usbRoots: [root, '/does/not/exist'] });
  const drives = await s.listDrives();
  assert.deepEqual(drives.map((d) => [d.label, d.path]).sort(), [['KINGSTON', path.join(root, 'alice', 'KINGSTON')], ['usb0', path.join(root, 'usb0')]]);
  const k = drives.find((d) => d.label === 'KINGSTON');
  assert.equal(k.id.includes('/'), false);
  assert.equal((await s.listDriveFiles(k.id)).entries[0].name, 'parts.csv');

  // A configured name with '..' inside (allowed by the cell schema) still works; unlisted ones with '..' do not.
  const odd = new DatabaseFiles({ cell: { database: { directory: 'db', files: ['v1..2.json'] } }, dataDir: tempDir(), usbRoots: [root] });
  assert.equal((await odd.replaceFromUpload('v1..2.json', streamOf('{}'), 'x.json', {})).backup, null);
  assert.equal((await odd.replaceFromUpload('v1..2.json', streamOf('[]'), 'x.json', {})).backup.startsWith('v1..2.json.'), true);
  assert.equal((await odd.listBackups('v1..2.json')).length, 1);
  await assert.rejects(odd.restoreBackup('v1..2.json', 'v1..2.json.../x', {}), { status: 400 });
  await assert.rejects(odd.listBackups('v1..3.json'), { status: 400 });

  assert.deepEqual(resolveUsbRoots('/a:/b', { database: { usb_roots: ['/media'] } }), ['/a', '/b']);
  assert.deepEqual(resolveUsbRoots('', { database: { usb_roots: ['/media'] } }), ['/media']);
  assert.deepEqual(resolveUsbRoots(undefined, {}), ['/media', '/run/media']);
});

test('replace from a drive keeps a backup; restore brings the old content back; both are audited', async () => {
  const t = await setup();
  try {
    const r = await t.req('POST', '/api/database/files/parts.csv/from-drive', { json: { drive: t.driveId, path: 'parts.csv' } });
    assert.equal(r.status, 200, r.text);
    assert.equal(fs.readFileSync(path.join(t.db, 'parts.csv'), 'utf8'), NEW_CSV);
    assert.match(r.data.backup, /^parts\.csv\.\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$/);
    assert.equal(fs.readFileSync(path.join(t.db, '.backups', r.data.backup), 'utf8'), OLD_CSV);
    assert.deepEqual(fs.readdirSync(t.db).filter((n) => n.endsWith('.tmp')), [], 'no temp files left');

    // Case-insensitive extension, subdirectory, ';' delimiter.
    const r2 = await t.req('POST', '/api/database/files/parts.csv/from-drive', { json: { drive: t.driveId, path: 'export/PARTS.CSV' } });
    assert.equal(r2.status, 200, r2.text);
    assert.match(fs.readFileSync(path.join(t.db, 'parts.csv'), 'utf8'), /from subdir/);

    const backups = await t.req('GET', '/api/database/files/parts.csv/backups');
    assert.equal(backups.data.backups.length, 2);
    assert.ok(backups.data.backups[0].name >= backups.data.backups[1].name, 'newest first');
    const oldest = backups.data.backups.at(-1).name;

    const rs = await t.req('POST', '/api/database/files/parts.csv/restore', { json: { backup: oldest } });
    assert.equal(rs.status, 200, rs.text);
    assert.equal(fs.readFileSync(path.join(t.db, 'parts.csv'), 'utf8'), OLD_CSV);
    assert.equal((await t.service.listBackups('parts.csv')).length, 3, 'the file replaced by the restore is kept too');

    // A new file (no old one): no backup.
    const j = await t.upload('recipes.json', 'recipes.JSON', '{"r": [1, 2]}');
    assert.equal(j.status, 200);
    assert.equal(j.data.backup, null);
    assert.equal(fs.readFileSync(path.join(t.db, 'recipes.json'), 'utf8'), '{"r": [1, 2]}');

    const y = await t.req('POST', '/api/database/files/fixtures.yaml/from-drive', { json: { drive: t.driveId, path: 'fixtures.yaml' } });
    assert.equal(y.status, 200);

    const rep = entries(t.audit, 'database.replace');
    assert.equal(rep.filter((e) => e.outcome === 'ok').length, 4);
    const first = rep.at(-1);
    assert.equal(first.user, 'ada');
    assert.equal(first.role, 'admin');
    assert.equal(first.target, 'parts.csv');
    assert.equal(first.ip, '127.0.0.1');
    assert.match(first.detail, /parts\.csv/);
    const res = entries(t.audit, 'database.restore');
    assert.equal(res.length, 1);
    assert.equal(res[0].outcome, 'ok');
    assert.ok(res[0].detail.includes(oldest));

    // Restore of an unknown or foreign backup.
    const nope = await t.req('POST', '/api/database/files/parts.csv/restore', { json: { backup: 'parts.csv.nope' } });
    assert.equal(nope.status, 404);
    assert.deepEqual(nope.data, { error: 'no backup parts.csv.nope', code: 'database.no_backup', params: { backup: 'parts.csv.nope' } });
    const foreign = await t.req('POST', '/api/database/files/parts.csv/restore', { json: { backup: 'fixtures.yaml.x' } });
    assert.equal(foreign.status, 400);
    assert.equal(foreign.data.code, 'database.invalid_backup');
    assert.deepEqual(foreign.data.params, { file: 'parts.csv' });
    assert.equal((await t.req('POST', '/api/database/files/parts.csv/restore', { json: { backup: '../../users.json' } })).status, 400);
    assert.equal(entries(t.audit, 'database.restore').filter((e) => e.outcome === 'denied').length, 3);
  } finally {
    await t.stop();
  }
});

test('path traversal is refused and nothing changes on disk', async () => {
  const t = await setup();
  try {
    const before = snapshot(t.dataDir);
    const d = encodeURIComponent(t.driveId);
    const cases = [
      // [method, url, json, expected status]
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: t.driveId, path: '../outside-drive.csv' }, 400],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: t.driveId, path: 'export/../../outside-drive.csv' }, 400],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: t.driveId, path: path.join(t.usb, 'outside-drive.csv') }, 400],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: t.driveId, path: '/etc/passwd' }, 400],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: t.driveId, path: 'parts.csv\u0000.csv' }, 400],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: t.driveId, path: 'passwd.csv' }, 403],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: t.driveId, path: 'secret.csv' }, 403],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: t.driveId, path: 'outdir/secret.csv' }, 403],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: '..', path: 'outside-drive.csv' }, 400],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: '0:STICK/..', path: 'outside-drive.csv' }, 400],
      ['POST', '/api/database/files/parts.csv/from-drive', { drive: '0:../..', path: 'etc/passwd' }, 400],
      // Target names in the URL: raw and percent-encoded.
      ['POST', '/api/database/files/../users.json/from-drive', { drive: t.driveId, path: 'parts.csv' }, 404], // no route: ../ is a path segment
      ['POST', '/api/database/files/..%2Fusers.json/from-drive', { drive: t.driveId, path: 'parts.csv' }, 400],
      ['POST', '/api/database/files/%2e%2e%2fusers.json/from-drive', { drive: t.driveId, path: 'parts.csv' }, 400],
      ['POST', '/api/database/files/%2e%2e/from-drive', { drive: t.driveId, path: 'parts.csv' }, 400],
      ['POST', '/api/database/files/%2Fetc%2Fpasswd/from-drive', { drive: t.driveId, path: 'parts.csv' }, 400],
      ['POST', '/api/database/files/parts.csv%00/from-drive', { drive: t.driveId, path: 'parts.csv' }, 400],
      ['POST', '/api/database/files/users.json/from-drive', { drive: t.driveId, path: 'parts.csv' }, 404],
      // Drive listing: drive ids and paths, raw and encoded.
      ['GET', '/api/database/drives/../files', undefined, 400],
      ['GET', '/api/database/drives/%2e%2e/files', undefined, 400],
      ['GET', '/api/database/drives/%2e%2e%2f%2e%2e%2fetc/files', undefined, 400],
      ['GET', `/api/database/drives/${d}/files?path=..`, undefined, 400],
      ['GET', `/api/database/drives/${d}/files?path=../..`, undefined, 400],
      ['GET', `/api/database/drives/${d}/files?path=%2e%2e%2f%2e%2e`, undefined, 400],
      ['GET', `/api/database/drives/${d}/files?path=%2Fetc`, undefined, 400],
      ['GET', `/api/database/drives/${d}/files?path=outdir`, undefined, 403],
      ['GET', `/api/database/drives/${d}/files?path=a&path=b`, undefined, 400],
      ['GET', '/api/database/files/%2e%2e%2fusers.json/backups', undefined, 400],
      ['POST', '/api/database/files/parts.csv/restore', { backup: '..%2f..%2fusers.json' }, 400],
    ];
    for (const [method, url, json, status] of cases) {
      const r = await t.req(method, url, { json });
      assert.equal(r.status, status, `${method} ${url} ${JSON.stringify(json)} -> ${r.status} ${r.text}`);
      if (r.status !== 404 || r.data) {
        assert.equal(typeof r.data?.error, 'string', `${url}: JSON error`);
        // Each refusal has a stable code for the app (database.invalid_path, database.outside_drive, ...).
        assert.match(String(r.data.code), /^database\.[a-z_]+$/, `${url}: code`);
      }
      assert.ok(!r.text.includes('root:'), 'no /etc/passwd content');
    }
    const outside = await t.req('POST', '/api/database/files/parts.csv/from-drive', { json: { drive: t.driveId, path: 'passwd.csv' } });
    assert.deepEqual(outside.data, { error: 'the path leads outside the drive', code: 'database.outside_drive' });
    assert.equal((await t.req('GET', `/api/database/drives/${d}/files?path=..`)).data.code, 'database.invalid_path');
    assert.equal((await t.req('GET', '/api/database/files/%2e%2e%2fusers.json/backups')).data.code, 'database.invalid_name');
    // Upload with a hostile client file name: only its extension counts; nothing is written outside.
    const up = await t.upload('parts.csv', '../../../../tmp/evil.csv', NEW_CSV);
    assert.equal(up.status, 200);
    assert.equal(fs.readFileSync(path.join(t.db, 'parts.csv'), 'utf8'), NEW_CSV);
    const after = snapshot(t.dataDir);
    for (const f of ['audit/audit.log', 'audit/audit.head']) { delete after[f]; delete before[f]; }
    const changed = Object.keys(after).filter((k) => after[k] !== before[k]).sort();
    assert.equal(changed.length, 2, `only the upload changed things: ${changed}`);
    assert.ok(changed.includes('database/parts.csv') && changed.some((k) => k.startsWith('database/.backups/parts.csv.')));
    // Each refused replace is audited as denied.
    const denied = entries(t.audit, 'database.replace').filter((e) => e.outcome === 'denied');
    assert.ok(denied.length >= 15, `denied entries: ${denied.length}`);
    assert.ok(denied.some((e) => e.target === '../users.json'));
  } finally {
    await t.stop();
  }
});

test('wrong extension (415), malformed content (422) and unlisted targets (404) change nothing', async () => {
  const t = await setup();
  try {
    const before = snapshot(t.db);
    const fromDrive = (name, p) => t.req('POST', `/api/database/files/${name}/from-drive`, { json: { drive: t.driveId, path: p } });
    let r = await fromDrive('parts.csv', 'parts.txt');
    assert.equal(r.status, 415);
    assert.match(r.data.error, /\.csv/);
    assert.equal(r.data.code, 'database.bad_extension');
    assert.deepEqual(r.data.params, { file: 'parts.csv', expected: '.csv', got: '.txt' });
    assert.equal((await t.upload('parts.csv', 'parts.xlsx', NEW_CSV)).status, 415);
    r = await t.upload('parts.csv', 'parts', NEW_CSV);
    assert.equal(r.status, 415);
    assert.deepEqual(r.data, { error: 'parts.csv needs a .csv file, not one without extension', code: 'database.bad_extension', params: { file: 'parts.csv', expected: '.csv', got: '' } });
    assert.equal((await fromDrive('fixtures.yaml', 'parts.csv')).status, 415);

    r = await fromDrive('parts.csv', 'bad.csv');
    assert.equal(r.status, 422);
    assert.match(r.data.error, /line 2 has 3 columns/);
    assert.deepEqual(r.data, {
      error: 'parts.csv not replaced: CSV line 2 has 3 columns, expected 2 (as in the first line)',
      code: 'database.csv_columns', params: { file: 'parts.csv', line: 2, columns: 3, expected: 2 },
    });
    r = await t.upload('parts.csv', 'p.csv', 'a,b\n"unclosed,1\n');
    assert.equal(r.status, 422);
    assert.deepEqual([r.data.code, r.data.params], ['database.csv_unclosed_quote', { file: 'parts.csv', line: 2 }]);
    r = await t.upload('parts.csv', 'p.csv', '');
    assert.equal(r.status, 422);
    assert.deepEqual(r.data, { error: 'parts.csv not replaced: the file is empty', code: 'database.empty_file', params: { file: 'parts.csv' } });
    r = await t.upload('parts.csv', 'p.csv', Buffer.from('\xff\xfea\x00,\x00b\x00', 'latin1'));
    assert.equal(r.status, 422, 'UTF-16');
    assert.equal(r.data.code, 'database.nul_bytes');
    r = await t.upload('recipes.json', 'r.json', '{"a": 1,,}');
    assert.equal(r.status, 422);
    assert.match(r.data.error, /JSON/);
    assert.equal(r.data.code, 'database.bad_json');
    assert.equal(r.data.params.file, 'recipes.json');
    assert.equal(r.data.error, `recipes.json not replaced: not valid JSON: ${r.data.params.detail}`);
    r = await fromDrive('fixtures.yaml', 'bad.yaml');
    assert.equal(r.status, 422);
    assert.match(r.data.error, /YAML/);
    assert.equal(r.data.code, 'database.bad_yaml');
    assert.equal(r.data.params.file, 'fixtures.yaml');
    assert.equal(r.data.error, `fixtures.yaml not replaced: not valid YAML: ${r.data.params.detail} (line ${r.data.params.line})`);

    r = await fromDrive('users.json', 'parts.csv');
    assert.equal(r.status, 404);
    assert.deepEqual(r.data, { error: 'users.json is not a database file of this cell', code: 'database.not_listed', params: { file: 'users.json' } });
    assert.equal((await t.upload('users.json', 'users.json', '{}')).status, 404);
    assert.equal((await t.upload('cell.yaml', 'cell.yaml', 'a: 1')).status, 404);
    assert.equal((await t.req('GET', '/api/database/files/users.json/backups')).status, 404);

    assert.deepEqual(snapshot(t.db), before);
    assert.equal(fs.readFileSync(path.join(t.dataDir, 'users.json'), 'utf8'), '{"secret": true}');
    assert.equal(fs.existsSync(path.join(t.dataDir, 'recipes.json')), false);
    const denied = entries(t.audit, 'database.replace').filter((e) => e.outcome === 'denied');
    assert.equal(denied.length, 13);
    assert.ok(fs.readdirSync(path.join(t.dataDir, '.uploads')).length === 0, 'upload spool is empty');
  } finally {
    await t.stop();
  }
});

test('too large: upload refused with 413 and its temp file removed; drive file too', async () => {
  const t = await setup({ maxBytes: 1000 });
  try {
    const before = snapshot(t.db);
    const big = 'a,b\n' + '1,2\n'.repeat(1000);
    const r = await t.upload('parts.csv', 'parts.csv', big);
    assert.equal(r.status, 413);
    assert.match(r.data.error, /1000 bytes/);
    assert.deepEqual(r.data, { error: 'the file is larger than the limit of 1000 bytes', code: 'database.too_large', params: { limit: 1000 } });
    assert.deepEqual(fs.readdirSync(path.join(t.dataDir, '.uploads')), [], 'spooled upload removed');
    assert.equal((await t.req('POST', '/api/database/files/parts.csv/from-drive', { json: { drive: t.driveId, path: 'big.csv' } })).status, 413);
    // Declared too large: refused before reading.
    const r3 = await t.req('POST', '/api/database/files/parts.csv/upload', { headers: { 'content-type': 'multipart/form-data; boundary=x' }, body: 'x'.repeat(70 * 1024) });
    assert.equal(r3.status, 413);
    assert.equal(r3.data.code, 'database.too_large');
    // Exactly at the limit passes.
    const exact = 'a,b\n' + '1,2\n'.repeat(249);
    assert.equal(exact.length, 1000);
    assert.equal((await t.upload('parts.csv', 'parts.csv', exact)).status, 200);
    assert.notDeepEqual(snapshot(t.db), before);
    assert.deepEqual(fs.readdirSync(path.join(t.dataDir, '.uploads')), []);
    assert.deepEqual(fs.readdirSync(t.db).filter((n) => n.endsWith('.tmp')), []);
    assert.equal(entries(t.audit, 'database.replace').filter((e) => e.outcome === 'denied').length, 3);

    // Not multipart, no file field.
    const notMultipart = await t.req('POST', '/api/database/files/parts.csv/upload', { json: { a: 1 } });
    assert.equal(notMultipart.status, 415);
    assert.equal(notMultipart.data.code, 'database.not_multipart');
    const fd = new FormData();
    fd.append('other', new Blob(['x']), 'parts.csv');
    const res = await fetch(`http://127.0.0.1:${t.port}/api/database/files/parts.csv/upload`, { method: 'POST', body: fd, headers: { 'x-test-user': 'ada' } });
    assert.equal(res.status, 400);
    assert.deepEqual(await res.json(), { error: 'unexpected file field ("other"); send one file, in the field "file"', code: 'database.one_file' });
  } finally {
    await t.stop();
  }
});

test('a failed write leaves the old file intact, removes the temp file and is audited as failed', async () => {
  const failingRename = { ...realFsp, rename: async () => { throw Object.assign(new Error('EIO: i/o error, rename'), { code: 'EIO' }); } };
  const t = await setup({ fsp: failingRename });
  try {
    const r = await t.req('POST', '/api/database/files/parts.csv/from-drive', { json: { drive: t.driveId, path: 'parts.csv' } });
    assert.equal(r.status, 500);
    assert.match(r.data.error, /EIO/);
    assert.equal(r.data.code, undefined, 'a server failure has no client code');
    assert.equal(fs.readFileSync(path.join(t.db, 'parts.csv'), 'utf8'), OLD_CSV);
    assert.deepEqual(fs.readdirSync(t.db).filter((n) => n.endsWith('.tmp')), [], 'temp file removed');
    assert.deepEqual(fs.existsSync(path.join(t.db, '.backups')) ? fs.readdirSync(path.join(t.db, '.backups')) : [], [], 'no stray backup');
    const u = await t.upload('parts.csv', 'parts.csv', NEW_CSV);
    assert.equal(u.status, 500);
    assert.equal(fs.readFileSync(path.join(t.db, 'parts.csv'), 'utf8'), OLD_CSV);
    const failed = entries(t.audit, 'database.replace').filter((e) => e.outcome === 'failed');
    assert.equal(failed.length, 2);
  } finally {
    await t.stop();
  }

  // A failing write in the middle of the copy (disk full).
  const failingWrite = {
    ...realFsp,
    open: async (...a) => {
      const fh = await realFsp.open(...a);
      if (a[1] === 'wx') fh.write = async () => { throw Object.assign(new Error('ENOSPC'), { code: 'ENOSPC' }); };
      return fh;
    },
  };
  const t2 = await setup({ fsp: failingWrite });
  try {
    const r = await t2.req('POST', '/api/database/files/parts.csv/from-drive', { json: { drive: t2.driveId, path: 'parts.csv' } });
    assert.equal(r.status, 500);
    assert.equal(fs.readFileSync(path.join(t2.db, 'parts.csv'), 'utf8'), OLD_CSV);
    assert.deepEqual(fs.readdirSync(t2.db).filter((n) => n.endsWith('.tmp')), []);
  } finally {
    await t2.stop();
  }
});

test('session and the database page are required', async () => {
  const t = await setup();
  try {
    assert.equal((await t.req('GET', '/api/database/files', { user: null })).status, 401);
    assert.equal((await t.req('GET', '/api/database/files', { user: 'olga' })).status, 403);
    const r = await t.req('POST', '/api/database/files/parts.csv/from-drive', { user: 'olga', json: { drive: t.driveId, path: 'parts.csv' } });
    assert.equal(r.status, 403);
    assert.equal((await t.upload('parts.csv', 'parts.csv', NEW_CSV, 'olga')).status, 403);
    assert.equal(fs.readFileSync(path.join(t.db, 'parts.csv'), 'utf8'), OLD_CSV);
    // Bad JSON bodies.
    const noPath = await t.req('POST', '/api/database/files/parts.csv/from-drive', { json: { drive: t.driveId } });
    assert.equal(noPath.status, 400);
    assert.deepEqual(noPath.data, { error: '"path" must be a non-empty string', code: 'request.invalid', params: { detail: '"path" must be a non-empty string' } });
    assert.equal((await t.req('POST', '/api/database/files/parts.csv/restore', { json: [] })).status, 400);
  } finally {
    await t.stop();
  }
});

test('serialised per target: concurrent replacements all succeed, each with a backup', async () => {
  const t = await setup();
  try {
    const rs = await Promise.all([1, 2, 3].map((i) => t.service.replaceFromUpload('parts.csv', streamOf(`id\n${i}\n`), 'p.csv', { username: 'ada', role: 'admin', ip: null })));
    assert.equal(new Set(rs.map((r) => r.backup)).size, 3);
    assert.equal((await t.service.listBackups('parts.csv')).length, 3);
  } finally {
    await t.stop();
  }
});

test('CSV checker and OpenAPI paths', () => {
  assert.deepEqual(checkCsv('a;b;c\r\n1;2;3\r\n'), { delimiter: ';', columns: 3, rows: 2 });
  assert.deepEqual(checkCsv('a,b\n"multi\nline",2\n\n'), { delimiter: ',', columns: 2, rows: 2 });
  assert.throws(() => checkCsv('a,b\n1\n'), /line 2/);
  assert.throws(() => checkCsv('a,b\n"x"y,1\n'), /closing quote/);
  for (const p of ['/api/database/files', '/api/database/drives', '/api/database/drives/{drive}/files', '/api/database/files/{name}/from-drive',
    '/api/database/files/{name}/upload', '/api/database/files/{name}/backups', '/api/database/files/{name}/restore']) {
    assert.ok(databaseOpenApiPaths[p], p);
  }
  assert.ok(databaseOpenApiPaths['/api/database/files/{name}/upload'].post.requestBody.content['multipart/form-data']);
});

async function* streamOf(s) {
  yield Buffer.from(s);
}
