import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import express from 'express';
import { tempDir } from '../helpers.js';
import { AuditLog } from '../../src/core/audit/audit-log.js';
import { requireSession, requirePage } from '../../src/core/http/guards.js';
import recorder, { Recordings, recorderRoutes } from '../../src/features/recorder/index.js';

const NAME = '20261126T140512.123Z-alarm-robot-protective-stop.mcap';
const MCAP = Buffer.concat([Buffer.from([0x89, 0x4d, 0x43, 0x41, 0x50, 0x30, 0x0d, 0x0a]), Buffer.alloc(5000, 7)]);
const SIDECAR = {
  version: 1, name: NAME, reason: 'alarm robot.protective_stop: Robot protective stop', at_ms: 1795700712123,
  start_ms: 1795700592123, end_ms: 1795700722123, duration_s: 130, size: MCAP.length, messages: 6500,
  alarms: ['robot.protective_stop'], topics: [{ topic: '/joint_states', type: 'sensor_msgs/JointState', count: 6500 }],
  timeline: { lanes: [
    { id: 'alarms', title: 'Alarms', changes: [{ t_ms: 1795700712123, text: 'robot.protective_stop: Robot protective stop' }] },
    { id: 'process', title: 'Process', changes: [{ t_ms: 1795700592123, text: 'running · Move to part 1' }, { t_ms: 'late', text: 'x' }] },
    { id: 'bogus', title: 'Not a lane', changes: [] },
  ] },
};

async function setup() {
  const dataDir = tempDir();
  const dir = path.join(dataDir, 'recordings');
  fs.mkdirSync(dir);
  fs.writeFileSync(path.join(dir, NAME), MCAP);
  fs.writeFileSync(path.join(dir, NAME.replace('.mcap', '.json')), JSON.stringify(SIDECAR));
  // By hand, no description; a torn description; a save in progress; not a recording.
  fs.writeFileSync(path.join(dir, 'copied-by-hand.mcap'), MCAP.subarray(0, 100));
  fs.utimesSync(path.join(dir, 'copied-by-hand.mcap'), 1000, 1000);
  fs.writeFileSync(path.join(dir, '20261126T150000.000Z-saved-by-hand.mcap'), MCAP.subarray(0, 200));
  fs.writeFileSync(path.join(dir, '20261126T150000.000Z-saved-by-hand.json'), '{"reason": "saved by h');
  fs.writeFileSync(path.join(dir, '.tmp-abc.mcap'), 'torn');
  fs.writeFileSync(path.join(dir, 'notes.txt'), 'x');
  fs.writeFileSync(path.join(dataDir, 'secret.mcap'), 'outside');
  const cell = {
    pages: [{ id: 'home' }, { id: 'recorder' }],
    roles: { admin: { pages: ['home', 'recorder'] }, operator: { pages: ['home', 'recorder'] }, guest: { pages: ['home'] } },
    recorder: { delete_roles: ['admin'] },
  };
  const audit = new AuditLog({ dir: path.join(dataDir, 'audit') });
  const app = express();
  app.use((req, res, next) => {
    const u = req.headers['x-test-user'];
    req.session = u ? { username: u, role: { ada: 'admin', olga: 'operator', gus: 'guest' }[u] } : null;
    next();
  });
  app.use(recorderRoutes({
    recordings: new Recordings({ dir }), canDelete: (role) => role === 'admin',
    guard: [requireSession, requirePage(cell, 'recorder')], audit, log: () => {},
  }));
  const server = http.createServer(app);
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  const port = server.address().port;
  return {
    dir, audit,
    async stop() { server.closeAllConnections(); await new Promise((r) => server.close(r)); },
    req(method, urlPath, user = 'ada') {
      return new Promise((resolve, reject) => {
        const rq = http.request({ host: '127.0.0.1', port, method, path: urlPath, headers: user ? { 'x-test-user': user } : {} }, (res) => {
          const chunks = [];
          res.on('data', (c) => chunks.push(c));
          res.on('end', () => {
            const body = Buffer.concat(chunks);
            let data = null;
            try { data = JSON.parse(body.toString()); } catch { /* a file */ }
            resolve({ status: res.statusCode, headers: res.headers, body, data });
          });
        });
        rq.on('error', reject);
        rq.end();
      });
    },
  };
}

test('the list: newest first, described by the JSON beside each file, the others by name, size and time', async () => {
  const s = await setup();
  try {
    const r = await s.req('GET', '/api/recorder/recordings');
    assert.equal(r.status, 200);
    assert.equal(r.data.can_delete, true);
    // The torn one is as new as its file (now), the copied one as old as its file (1970).
    assert.deepEqual(r.data.recordings.map((x) => x.name), ['20261126T150000.000Z-saved-by-hand.mcap', NAME, 'copied-by-hand.mcap']);
    const byName = Object.fromEntries(r.data.recordings.map((x) => [x.name, x]));
    assert.deepEqual(byName[NAME], {
      name: NAME, at_ms: SIDECAR.at_ms, reason: SIDECAR.reason, size: MCAP.length, duration_s: 130, messages: 6500, alarms: ['robot.protective_stop'],
    });
    assert.deepEqual(byName['copied-by-hand.mcap'], { name: 'copied-by-hand.mcap', at_ms: 1_000_000, reason: '', size: 100, duration_s: 0, messages: 0, alarms: [] });
    assert.equal(byName['20261126T150000.000Z-saved-by-hand.mcap'].reason, ''); // a torn description: listed all the same
    assert.equal((await s.req('GET', '/api/recorder/recordings', 'olga')).data.can_delete, false);
    assert.equal((await s.req('GET', '/api/recorder/recordings', 'gus')).status, 403);
    assert.equal((await s.req('GET', '/api/recorder/recordings', null)).status, 401);
  } finally {
    await s.stop();
  }
});

test('one recording: its topics and timeline, only the lanes and changes that make sense', async () => {
  const s = await setup();
  try {
    const r = await s.req('GET', `/api/recorder/recordings/${NAME}`, 'olga');
    assert.equal(r.status, 200);
    assert.equal(r.data.start_ms, SIDECAR.start_ms);
    assert.deepEqual(r.data.topics, SIDECAR.topics);
    assert.deepEqual(r.data.timeline.lanes.map((l) => [l.id, l.changes.length]), [['alarms', 1], ['process', 1]]);
    const nope = await s.req('GET', '/api/recorder/recordings/nope.mcap');
    assert.equal(nope.status, 404);
    assert.deepEqual(nope.data, { error: 'no recording nope.mcap', code: 'recorder.not_found', params: { name: 'nope.mcap' } });
    for (const bad of ['..%2Fsecret.mcap', '.tmp-abc.mcap', 'notes.txt', '%2Fetc%2Fpasswd']) {
      const b = await s.req('GET', `/api/recorder/recordings/${bad}`);
      assert.equal(b.status, 400, bad);
      assert.match(b.data.error, /not a recording's name/);
      assert.equal(b.data.code, 'recorder.invalid_name', bad);
      assert.equal(b.data.params.name, decodeURIComponent(bad), bad);
    }
  } finally {
    await s.stop();
  }
});

test('a download is the file itself, as an attachment, and is audited', async () => {
  const s = await setup();
  try {
    const r = await s.req('GET', `/api/recorder/recordings/${NAME}/file`, 'olga');
    assert.equal(r.status, 200);
    assert.ok(r.body.equals(MCAP));
    assert.equal(r.headers['content-disposition'], `attachment; filename="${NAME}"`);
    assert.equal((await s.req('GET', '/api/recorder/recordings/..%2Fsecret.mcap/file')).status, 400);
    const gone = await s.req('GET', '/api/recorder/recordings/gone.mcap/file');
    assert.equal(gone.status, 404);
    assert.deepEqual([gone.data.code, gone.data.params], ['recorder.not_found', { name: 'gone.mcap' }]);
    const entries = s.audit.query({ op: 'recorder.download' }).entries;
    assert.deepEqual(entries.map((e) => [e.user, e.target, e.outcome]).sort(), [
      ['ada', '../secret.mcap', 'denied'], ['ada', 'gone.mcap', 'denied'], ['olga', NAME, 'ok'],
    ]);
  } finally {
    await s.stop();
  }
});

test('only the roles the cell file names delete, the description goes with the file, both audited', async () => {
  const s = await setup();
  try {
    const refused = await s.req('DELETE', `/api/recorder/recordings/${NAME}`, 'olga');
    assert.equal(refused.status, 403);
    assert.deepEqual(refused.data, { error: 'role operator may not delete recordings', code: 'recorder.delete_denied', params: { role: 'operator' } });
    assert.ok(fs.existsSync(path.join(s.dir, NAME)));
    const ok = await s.req('DELETE', `/api/recorder/recordings/${NAME}`, 'ada');
    assert.deepEqual([ok.status, ok.data], [200, { deleted: NAME }]);
    assert.deepEqual(fs.readdirSync(s.dir).filter((n) => n.startsWith('20261126T14')), []);
    assert.equal((await s.req('DELETE', `/api/recorder/recordings/${NAME}`, 'ada')).status, 404);
    const entries = s.audit.query({ op: 'recorder.delete' }).entries;
    assert.deepEqual(entries.map((e) => [e.user, e.outcome]).sort(), [['ada', 'denied'], ['ada', 'ok'], ['olga', 'denied']]);
  } finally {
    await s.stop();
  }
});

test('the feature: the page reads the state and saves with the commands grant; delete_roles must be roles', () => {
  const cell = { roles: { admin: {}, operator: {} } };
  assert.deepEqual(recorder.check({ delete_roles: ['admin', 'boss'] }, /** @type {any} */ (cell)), ['recorder.delete_roles[1]: no role "boss" in roles']);
  assert.deepEqual(recorder.view({ before_s: 30, delete_roles: ['admin'] }, 'operator', /** @type {any} */ (cell)), { before_s: 30, after_s: 10, can_delete: false });
  assert.deepEqual(recorder.reads({}, /** @type {any} */ (cell)), { subscribe: ['/cell/recorder/state'] });
  assert.deepEqual(recorder.commands({}, /** @type {any} */ (cell)), { call_service: ['/cell/recorder/save'] });
});
