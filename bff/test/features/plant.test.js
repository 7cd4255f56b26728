// The plant feature's parts without a broker: Sparkplug payloads (decoded back with Tahu's library), the cell's
// report from its state topics, report by exception, and the host's view of births, data, deaths and rebirths.
import { test } from 'node:test';
import { EventEmitter } from 'node:events';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import sparkplug from 'sparkplug-payload';
import { EdgeSession, cellMetrics, decode, parseTopic, topicOf, asksRebirth, rebirthCommand } from '../../src/features/plant/sparkplug.js';
import { CellReport, cellShape } from '../../src/features/plant/report.js';
import { PlantHost } from '../../src/features/plant/host.js';
import { EdgeNode } from '../../src/features/plant/edge-node.js';
import { ShiftStats } from '../../src/features/plant/shift.js';
import { brokerOptions } from '../../src/features/plant/mqtt-link.js';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { tempDir, startBff, login } from '../helpers.js';

const codec = sparkplug.get('spBv1.0');
const demo = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
const twin = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/twin-arm-cell.yaml'), 'utf8')));
const byName = (/** @type {any} */ p) => Object.fromEntries(p.metrics.map((/** @type {any} */ m) => [m.name, m]));

test('topics: an edge node message is parsed, STATE and malformed names are not', () => {
  assert.equal(topicOf('plant-a', 'NBIRTH', 'demo-ur5'), 'spBv1.0/plant-a/NBIRTH/demo-ur5');
  assert.deepEqual(parseTopic('spBv1.0/plant-a/NDATA/demo-ur5'), { group: 'plant-a', type: 'NDATA', node: 'demo-ur5', device: null });
  assert.deepEqual(parseTopic('spBv1.0/plant-a/DDATA/demo-ur5/cam'), { group: 'plant-a', type: 'DDATA', node: 'demo-ur5', device: 'cam' });
  for (const t of ['spBv1.0/STATE/host', 'spBv1.0/plant-a/NFOO/x', 'spAv1.0/plant-a/NDATA/x', 'spBv1.0//NDATA/x', 'spBv1.0/a/NDATA/b/c/d']) {
    assert.equal(parseTopic(t), null, t);
  }
});

test('NBIRTH: bdSeq, Node Control/Rebirth and every metric of the cell, seq 0; unknown values are null', () => {
  const s = new EdgeSession(cellMetrics(cellShape(twin)));
  s.bdSeq = 7;
  const raw = codec.decodePayload(s.birth({ Mode: 'running', 'Alarms/Active': 2 }, 1_795_000_000_000));
  assert.equal(Number(raw.seq), 0);
  assert.equal(Number(raw.timestamp), 1_795_000_000_000);
  const m = byName(raw);
  assert.equal(Number(m.bdSeq.value), 7);
  assert.equal(m.bdSeq.type, 'UInt64');
  assert.deepEqual([m['Node Control/Rebirth'].type, m['Node Control/Rebirth'].value], ['Boolean', false]);
  assert.deepEqual([m.Mode.type, m.Mode.value], ['String', 'running']);
  assert.deepEqual([m['Alarms/Active'].type, m['Alarms/Active'].value], ['UInt32', 2]);
  // One robot metric pair per motion group of the twin cell, one per module.
  for (const g of twin.manual.groups) assert.ok(m[`Robot/${g.name}/Connected`] && m[`Robot/${g.name}/Mode`], g.name);
  for (const x of twin.modules) assert.ok(m[`Modules/${x.name}`], x.name);
  assert.equal(m['Process/State'].value, null);
});

test('NDATA: only what changed (report by exception), seq counts 1..255 then 0, nothing when nothing changed', () => {
  const s = new EdgeSession(cellMetrics(cellShape(demo)));
  s.birth({ Mode: 'idle', 'Alarms/Active': 0 }, 1);
  assert.equal(s.data({ Mode: 'idle', 'Alarms/Active': 0 }, 2), null);
  const p = decode(/** @type {Uint8Array} */ (s.data({ Mode: 'running', 'Alarms/Active': 0 }, 3)));
  assert.equal(p?.seq, 1);
  assert.deepEqual(p?.metrics.map((m) => [m.name, m.value]), [['Mode', 'running']]);
  // A value that goes unknown is reported as null (is_null), once.
  const q = decode(/** @type {Uint8Array} */ (s.data({ 'Alarms/Active': 0 }, 4)));
  assert.deepEqual(q?.metrics.map((m) => [m.name, m.value]), [['Mode', null]]);
  assert.equal(s.data({ 'Alarms/Active': 0 }, 5), null);
  let last = 2;
  for (let i = 0; i < 300; i++) {
    const seq = decode(/** @type {Uint8Array} */ (s.data({ 'Alarms/Active': i + 1 }, 6)))?.seq;
    assert.equal(seq, (last + 1) % 256);
    last = /** @type {number} */ (seq);
  }
  // A rebirth starts again at 0 and carries everything.
  assert.equal(decode(s.birth({}, 7))?.seq, 0);
});

test('NDEATH carries the bdSeq of its connection; the next connection the next one', () => {
  const s = new EdgeSession(cellMetrics(cellShape(demo)));
  assert.equal(decode(s.death(1))?.metrics[0].value, 0);
  s.nextConnection();
  assert.deepEqual(decode(s.death(1))?.metrics.map((m) => [m.name, m.value]), [['bdSeq', 1]]);
  for (let i = 0; i < 255; i++) s.nextConnection();
  assert.equal(decode(s.death(1))?.metrics[0].value, 0);
});

test('a rebirth request is recognised; other commands and garbage are not', () => {
  assert.equal(asksRebirth(rebirthCommand(1)), true);
  assert.equal(asksRebirth(codec.encodePayload({ metrics: [{ name: 'Node Control/Rebirth', type: 'Boolean', value: false }] })), false);
  assert.equal(asksRebirth(codec.encodePayload({ metrics: [{ name: 'Mode', type: 'String', value: 'x' }] })), false);
  assert.equal(asksRebirth(new Uint8Array([0xff, 0xff, 0xff])), false);
});

test('the report: values from the cell\'s state topics; with the ROS link down nothing is claimed', () => {
  const r = new CellReport(demo, { url: 'http://cell-a:8080/' });
  assert.deepEqual(r.shape.topics.map((t) => t.topic).sort(), [
    '/cell/alarms/status', '/cell/manual/arm/state', '/cell/mode', '/cell/modules/state', '/cell/process/state',
  ]);
  r.setRos(true);
  r.onMessage('/cell/mode', { mode: 'running', source: 'process' });
  r.onMessage('/cell/alarms/status', { status: 'protective stop', text: 'Robot protective stop', active_count: 1, highest_severity: 2 });
  r.onMessage('/cell/process/state', { state: 'running', operations: ['Pick', 'Place'], current: 1, cycles_done: 4, last_cycle_s: 8.5 });
  r.onMessage('/cell/manual/arm/state', { connected: true, robot_mode: 'RUNNING' });
  r.onMessage('/cell/modules/state', { modules: [{ name: 'Vision', state: 'active' }] });
  const v = r.values();
  assert.deepEqual([v['Properties/Name'], v['Properties/URL'], v['ROS/Connected'], v.Mode], ['Demo UR5 cell', 'http://cell-a:8080/', true, 'running']);
  assert.deepEqual([v['Safety/Status'], v['Alarms/Active'], v['Alarms/Most severe'], v['Alarms/Highest severity']], ['protective stop', 1, 'Robot protective stop', 2]);
  assert.deepEqual([v['Process/State'], v['Process/Operation'], v['Process/Cycles done'], v['Process/Last cycle time']], ['running', 'Place', 4, 8.5]);
  assert.deepEqual([v['Robot/arm/Connected'], v['Robot/arm/Mode'], v['Modules/Vision'], v['Modules/Simulated cell']], [true, 'RUNNING', 'active', null]);
  r.onMessage('/cell/process/state', { state: 'idle', operations: ['Pick'], current: 0, cycles_done: 4, last_cycle_s: 8.5 });
  assert.equal(r.values()['Process/Operation'], '');
  r.setRos(false);
  const down = r.values();
  assert.equal(down['ROS/Connected'], false);
  assert.deepEqual([down.Mode, down['Alarms/Active'], down['Process/State'], down['Robot/arm/Connected']], [null, null, null, null]);
  assert.equal(down['Properties/Name'], 'Demo UR5 cell');
});

/** A host fed by hand, with what it sends. */
function host(now = { t: 1000 }) {
  /** @type {string[]} */
  const sent = [];
  /** @type {string[]} */
  const logs = [];
  let changes = 0;
  const h = new PlantHost({ groups: ['plant-a'], send: (t, p) => { assert.equal(asksRebirth(p), true); sent.push(t); }, onChange: () => changes++, log: (m) => logs.push(m), now: () => now.t });
  return { h, sent, logs, now, changes: () => changes };
}

test('the host: a birth lists the cell, data updates it, its death marks it offline since then', () => {
  const { h, now, changes } = host();
  const s = new EdgeSession(cellMetrics(cellShape(demo)));
  h.onMessage('spBv1.0/plant-a/NBIRTH/demo-ur5', s.birth({ 'Properties/Name': 'Demo UR5 cell', 'Properties/URL': 'http://a/', 'ROS/Connected': true, Mode: 'idle', 'Alarms/Active': 0, 'Alarms/Highest severity': -1, 'Robot/arm/Connected': true, 'Robot/arm/Mode': 'RUNNING', 'Modules/Vision': 'active' }, 1));
  let [c] = h.cells();
  assert.deepEqual([c.id, c.name, c.url, c.online, c.since, c.mode, c.alarms, c.severity, c.ros], ['plant-a/demo-ur5', 'Demo UR5 cell', 'http://a/', true, 1000, 'idle', 0, -1, true]);
  assert.deepEqual(c.robots, [{ group: 'arm', connected: true, mode: 'RUNNING' }]);
  assert.deepEqual(c.modules.find((m) => m.name === 'Vision'), { name: 'Vision', state: 'active' });
  now.t = 2000;
  h.onMessage('spBv1.0/plant-a/NDATA/demo-ur5', /** @type {Uint8Array} */ (s.data({ 'Properties/Name': 'Demo UR5 cell', 'Properties/URL': 'http://a/', 'ROS/Connected': true, Mode: 'alarm', 'Alarms/Active': 1, 'Alarms/Most severe': 'Door open', 'Alarms/Highest severity': 2, 'Robot/arm/Connected': true, 'Robot/arm/Mode': 'RUNNING', 'Modules/Vision': 'active' }, 2)));
  [c] = h.cells();
  assert.deepEqual([c.mode, c.alarms, c.alarm, c.severity, c.since, c.updated], ['alarm', 1, 'Door open', 2, 1000, 2000]);
  now.t = 3000;
  h.onMessage('spBv1.0/plant-a/NDEATH/demo-ur5', s.death(3));
  [c] = h.cells();
  assert.deepEqual([c.online, c.since, c.alarms], [false, 3000, 1]);
  assert.equal(changes(), 3);
});

test('the host: an old connection\'s will does not kill a node born again; another group and devices are ignored', () => {
  const { h } = host();
  const s = new EdgeSession(cellMetrics(cellShape(demo)));
  const oldDeath = s.death(1);
  s.nextConnection();
  h.onMessage('spBv1.0/plant-a/NBIRTH/demo-ur5', s.birth({}, 2));
  h.onMessage('spBv1.0/plant-a/NDEATH/demo-ur5', oldDeath);
  assert.equal(h.cells()[0].online, true);
  h.onMessage('spBv1.0/plant-b/NBIRTH/other', s.birth({}, 3));
  h.onMessage('spBv1.0/plant-a/DBIRTH/demo-ur5/cam', s.birth({}, 3));
  assert.equal(h.cells().length, 1);
});

test('the host asks for a rebirth on data before a birth and on a seq gap (at most every 5 s per node)', () => {
  const { h, sent, now } = host();
  const s = new EdgeSession(cellMetrics(cellShape(demo)));
  s.birth({}, 1);
  h.onMessage('spBv1.0/plant-a/NDATA/demo-ur5', /** @type {Uint8Array} */ (s.data({ Mode: 'idle' }, 2)));
  h.onMessage('spBv1.0/plant-a/NDATA/demo-ur5', /** @type {Uint8Array} */ (s.data({ Mode: 'running' }, 2)));
  assert.deepEqual(sent, ['spBv1.0/plant-a/NCMD/demo-ur5']);
  assert.equal(h.cells().length, 0);
  now.t += 6000;
  h.onMessage('spBv1.0/plant-a/NBIRTH/demo-ur5', s.birth({ Mode: 'idle' }, 3));
  s.data({ Mode: 'running' }, 4); // lost on the way
  h.onMessage('spBv1.0/plant-a/NDATA/demo-ur5', /** @type {Uint8Array} */ (s.data({ Mode: 'paused' }, 5)));
  assert.equal(h.cells()[0].mode, 'paused');
  assert.equal(sent.length, 2);
});

test('the host ignores a malformed payload with a log line', () => {
  const { h, logs } = host();
  h.onMessage('spBv1.0/plant-a/NBIRTH/bad', Buffer.from('{"not":"protobuf"}'.repeat(3)));
  assert.equal(h.cells().length, 0);
  assert.match(logs[0], /ignored a message on spBv1.0\/plant-a\/NBIRTH\/bad that is not a Sparkplug B payload/);
});

test('broker credentials come from the environment or the file the section names, never the cell file', () => {
  const dataDir = tempDir();
  fs.writeFileSync(path.join(dataDir, 'mqtt.cred'), 'cell-a\ns3cret\n');
  const section = { broker: 'mqtt://broker:1883', group_id: 'g', credentials_file: 'mqtt.cred' };
  const none = { brokerUrl: '', cellUrl: '', username: '', password: '' };
  assert.deepEqual(brokerOptions(section, { dataDir, plant: none }), { url: 'mqtt://broker:1883', options: { username: 'cell-a', password: 's3cret' } });
  const o = brokerOptions(section, { dataDir, plant: { ...none, brokerUrl: 'mqtt://other:1884', username: 'u', password: 'p' } });
  assert.deepEqual(o, { url: 'mqtt://other:1884', options: { username: 'u', password: 'p' } });
});

test('the plant page API: for the roles granted its page; with no broker it answers with the link down and no cells', async () => {
  const t = await startBff();
  try {
    const admin = (await login(t.base, 'admin', t.passwords.admin)).cookie;
    const operator = (await login(t.base, 'operator', t.passwords.operator)).cookie;
    const r = await fetch(`${t.base}/api/plant/cells`, { headers: { cookie: admin } });
    assert.equal(r.status, 200);
    const body = await r.json();
    assert.deepEqual(body.cells, []);
    assert.ok(['connecting', 'down'].includes(body.broker.state), body.broker.state);
    assert.equal((await fetch(`${t.base}/api/plant/cells`, { headers: { cookie: operator } })).status, 403);
    assert.equal((await fetch(`${t.base}/api/plant/events`, { headers: { cookie: operator } })).status, 403);
    assert.equal((await fetch(`${t.base}/api/plant/cells`)).status, 401);
    // The events: the same snapshot at once.
    const ac = new AbortController();
    const ev = await fetch(`${t.base}/api/plant/events`, { headers: { cookie: admin }, signal: ac.signal });
    assert.equal(ev.headers.get('content-type'), 'text/event-stream');
    const reader = /** @type {ReadableStream<Uint8Array>} */ (ev.body).getReader();
    let text = '';
    while (!text.includes('\n\n')) text += new TextDecoder().decode((await reader.read()).value);
    assert.match(text, /^event: cells\ndata: \{"broker":\{"state":"(connecting|down)"/);
    ac.abort();
    // The System page's health names the broker and both links.
    const health = await (await fetch(`${t.base}/api/system`, { headers: { cookie: admin } })).json();
    assert.equal(health.health.plant.broker, 'mqtt://127.0.0.1:1');
    assert.equal(health.health.plant.group_id, 'demo-plant');
    assert.equal(health.health.plant.edge_node_id, 'demo-ur5');
  } finally { await t.stop(); }
});

test('a cell file without a plant section: the page API says so', async () => {
  const cell = yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8'));
  delete cell.plant;
  const file = path.join(tempDir(), 'cell.yaml');
  fs.writeFileSync(file, yaml.dump(cell));
  const t = await startBff({ CELL_CONFIG: file });
  try {
    const admin = (await login(t.base, 'admin', t.passwords.admin)).cookie;
    const r = await fetch(`${t.base}/api/plant/cells`, { headers: { cookie: admin } });
    assert.equal(r.status, 404);
    assert.match((await r.json()).error, /no plant section/);
    assert.equal((await (await fetch(`${t.base}/api/health`)).json()).plant, undefined);
  } finally { await t.stop(); }
});

/** An mqtt.js client stand-in: records what is published, lets the test fire its events. */
function fakeMqtt() {
  /** @type {{topic: string, payload: Buffer}[]} */
  const published = [];
  /** @type {any} */
  let client;
  const connect = (/** @type {string} */ url, /** @type {any} */ options) => {
    client = new EventEmitter();
    Object.assign(client, {
      options, connected: false, published,
      publish: (/** @type {string} */ topic, /** @type {Buffer} */ payload, /** @type {any} */ o, /** @type {any} */ cb) => { published.push({ topic, payload }); if (typeof cb === 'function') cb(); },
      subscribe: () => {}, end: () => { client.connected = false; },
    });
    return client;
  };
  return { connect, published, client: () => client };
}

test('the edge node: birth on connect, changes at most every min_interval_ms, rebirth on NCMD and on a host coming online, NDEATH on close', async (t) => {
  t.mock.timers.enable({ apis: ['setTimeout', 'Date'], now: 1_000_000 });
  const f = fakeMqtt();
  const values = /** @type {Record<string, any>} */ ({ Mode: 'idle', 'Alarms/Active': 0 });
  const node = new EdgeNode({ url: 'mqtt://b', options: {}, groupId: 'g', nodeId: 'n', defs: cellMetrics(cellShape(demo)), values: () => values, minIntervalMs: 200, connect: /** @type {any} */ (f.connect) });
  const c = f.client();
  // bdSeq starts anywhere (a restarted BFF does not repeat its last), the client id is the node's own.
  const b0 = /** @type {number} */ (decode(c.options.will.payload)?.metrics[0].value);
  assert.ok(Number.isInteger(b0) && b0 >= 0 && b0 < 256);
  assert.equal(c.options.will.topic, 'spBv1.0/g/NDEATH/n');
  assert.equal(c.options.clientId, 'cell-g-n');
  c.connected = true;
  c.emit('connect');
  assert.deepEqual(f.published.map((p) => p.topic), ['spBv1.0/g/NBIRTH/n']);
  t.mock.timers.tick(1000);
  values.Mode = 'running';
  node.changed();
  assert.equal(f.published.length, 2, 'the first change goes at once');
  values['Alarms/Active'] = 1;
  node.changed();
  values.Mode = 'alarm';
  node.changed();
  assert.equal(f.published.length, 2, 'changes within the interval wait');
  t.mock.timers.tick(200);
  assert.equal(f.published.length, 3);
  assert.deepEqual(decode(f.published[2].payload)?.metrics.map((m) => [m.name, m.value]), [['Mode', 'alarm'], ['Alarms/Active', 1]]);
  c.emit('message', 'spBv1.0/g/NCMD/n', Buffer.from(rebirthCommand(1)), { retain: false });
  assert.equal(f.published.at(-1)?.topic, 'spBv1.0/g/NBIRTH/n');
  const n = f.published.length;
  c.emit('message', 'spBv1.0/STATE/host-a', Buffer.from('{"online":true,"timestamp":1}'), { retain: true });
  assert.equal(f.published.length, n, 'a retained STATE: the birth on connecting covered it');
  c.emit('message', 'spBv1.0/STATE/host-a', Buffer.from('{"online":true,"timestamp":2}'), { retain: false });
  assert.equal(f.published.at(-1)?.topic, 'spBv1.0/g/NBIRTH/n');
  c.emit('message', 'spBv1.0/STATE/host-a', Buffer.from('not json'), { retain: false });
  // The connection drops: the next CONNECT's will carries the next bdSeq.
  c.connected = false;
  c.emit('close');
  assert.equal(decode(c.options.will.payload)?.metrics[0].value, (b0 + 1) % 256);
  c.connected = true;
  c.emit('connect');
  assert.equal(decode(f.published.at(-1)?.payload ?? Buffer.alloc(0))?.metrics.find((m) => m.name === 'bdSeq')?.value, (b0 + 1) % 256);
  node.close();
  assert.equal(f.published.at(-1)?.topic, 'spBv1.0/g/NDEATH/n');
});

test('shift statistics: cycles in the last hour across runs, the share of the shift spent running (offline is not)', () => {
  const H = 3600_000;
  const s = new ShiftStats({ shiftMs: 8 * H });
  s.observe(0, { online: true, mode: 'idle', cycles: 0 });
  s.observe(0.5 * H, { online: true, mode: 'running', cycles: 0 });
  s.observe(0.75 * H, { online: true, mode: 'running', cycles: 5 });
  s.observe(1.25 * H, { online: true, mode: 'running', cycles: 9 });
  // A new run counts from 0 again: its 2 cycles are new ones.
  s.observe(1.3 * H, { online: true, mode: 'running', cycles: 2 });
  s.observe(1.5 * H, { online: false, mode: 'running', cycles: 2 });
  s.observe(2 * H, { online: true, mode: 'idle', cycles: 2 });
  let st = s.stats(2 * H);
  assert.equal(st.cycles_last_hour, 4 + 2, 'the 5 at 0.75 h are more than an hour old');
  assert.equal(st.observed_s, 7200);
  assert.ok(Math.abs(/** @type {number} */ (st.running_share) - 0.5) < 1e-9, String(st.running_share)); // 0.5 h to 1.5 h of 2 h
  // Later than the shift: only its last 8 h count (idle since 2 h).
  st = s.stats(10 * H);
  assert.equal(st.cycles_last_hour, 0);
  assert.equal(st.observed_s, 8 * 3600);
  assert.equal(st.running_share, 0);
  assert.equal(new ShiftStats().stats(5).running_share, null);
});

test('the host gives each cell its shift statistics', () => {
  const { h, now } = host();
  const s = new EdgeSession(cellMetrics(cellShape(demo)));
  h.onMessage('spBv1.0/plant-a/NBIRTH/demo-ur5', s.birth({ Mode: 'running', 'Process/Cycles done': 1 }, 1));
  now.t += 60_000;
  h.onMessage('spBv1.0/plant-a/NDATA/demo-ur5', /** @type {Uint8Array} */ (s.data({ Mode: 'running', 'Process/Cycles done': 4 }, 2)));
  now.t += 60_000;
  h.onMessage('spBv1.0/plant-a/NDATA/demo-ur5', /** @type {Uint8Array} */ (s.data({ Mode: 'idle', 'Process/Cycles done': 4 }, 3)));
  now.t += 120_000;
  assert.deepEqual(h.cells()[0].shift, { cycles_last_hour: 3, running_share: 0.5, observed_s: 240 });
});
