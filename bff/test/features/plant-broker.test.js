// The plant feature against a real broker (Debian's mosquitto): the demo cell's and the twin cell's BFFs, each a
// process of its own, report as Sparkplug B edge nodes; a Sparkplug host written here with Tahu's decoder sees both
// births and every change; SIGKILL of one BFF gives its NDEATH (the broker's will) within the keep-alive; a dead
// broker changes nothing for the cell's own API, and the cell is born again when the broker is back.
// Each BFF reads its cell's state from a rosbridge stand-in (the rosbridge v2 JSON ops it subscribes with): the
// whole stack with the real rosbridge is the e2e plant test's.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import path from 'node:path';
import yaml from 'js-yaml';
import mqtt from 'mqtt';
import sparkplug from 'sparkplug-payload';
import { WebSocketServer } from 'ws';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { tempDir } from '../helpers.js';

const codec = sparkplug.get('spBv1.0');
const KEEPALIVE_S = 2;
/** @type {(() => void)[]} */
const cleanup = [];
after(() => { for (const c of cleanup.reverse()) c(); });

/** @returns {Promise<number>} */
const freePort = () => new Promise((resolve) => {
  const s = net.createServer().listen(0, '127.0.0.1', () => { const { port } = /** @type {net.AddressInfo} */ (s.address()); s.close(() => resolve(port)); });
});

/** @param {() => boolean | Promise<boolean>} pred @param {number} ms @param {string} what */
async function until(pred, ms, what) {
  const end = Date.now() + ms;
  while (!(await pred())) {
    if (Date.now() > end) throw new Error(`timed out after ${ms} ms waiting for ${what}`);
    await new Promise((r) => setTimeout(r, 20));
  }
}

const reachable = (/** @type {number} */ port) => new Promise((resolve) => {
  const s = net.connect({ host: '127.0.0.1', port });
  s.once('connect', () => { s.destroy(); resolve(true); });
  s.once('error', () => resolve(false));
});

/** @param {number} port */
async function mosquitto(port) {
  const dir = tempDir('mosquitto-');
  fs.writeFileSync(path.join(dir, 'm.conf'), `listener ${port} 127.0.0.1\nallow_anonymous true\npersistence false\n`);
  const p = spawn('/usr/sbin/mosquitto', ['-c', path.join(dir, 'm.conf')], { stdio: 'ignore' });
  cleanup.push(() => p.kill('SIGKILL'));
  await until(() => reachable(port), 10_000, 'mosquitto');
  return p;
}

/** A TCP relay to the broker that can go silent without closing anything (a cable pulled). @param {number} to */
async function halfOpenProxy(to) {
  let frozen = false;
  /** @type {net.Socket[]} */
  const held = [];
  const server = net.createServer((a) => {
    const b = net.connect({ host: '127.0.0.1', port: to });
    held.push(a, b);
    a.on('data', (d) => { if (!frozen) b.write(d); });
    b.on('data', (d) => { if (!frozen) a.write(d); });
    a.on('error', () => {});
    b.on('error', () => {});
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', () => r(null)));
  cleanup.push(() => { for (const x of held) x.destroy(); server.close(); });
  return { port: /** @type {net.AddressInfo} */ (server.address()).port, freeze: () => { frozen = true; } };
}

/** A rosbridge stand-in: remembers what each client subscribed and publishes to it. */
async function rosbridge() {
  const wss = new WebSocketServer({ port: 0, host: '127.0.0.1' });
  await new Promise((r) => wss.once('listening', r));
  /** @type {Map<import('ws').WebSocket, Set<string>>} */
  const subs = new Map();
  wss.on('connection', (ws) => {
    subs.set(ws, new Set());
    ws.on('message', (d) => { const m = JSON.parse(d.toString()); if (m.op === 'subscribe') subs.get(ws)?.add(m.topic); });
    ws.on('close', () => subs.delete(ws));
  });
  cleanup.push(() => wss.close());
  return {
    port: /** @type {import('node:net').AddressInfo} */ (wss.address()).port,
    subscribed: (/** @type {string} */ t) => [...subs.values()].some((s) => s.has(t)),
    publish: (/** @type {string} */ topic, /** @type {any} */ msg) => {
      for (const [ws, s] of subs) if (s.has(topic)) ws.send(JSON.stringify({ op: 'publish', topic, msg }));
    },
  };
}

/** A cell's BFF as its own process, with an admin user. @param {string} cellFile @param {number} rosbridgePort @param {string} broker */
async function cellBff(cellFile, rosbridgePort, broker) {
  const dataDir = tempDir();
  const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, cellFile), 'utf8')));
  cell.plant.keepalive_s = KEEPALIVE_S;
  const file = path.join(dataDir, 'cell.yaml');
  fs.writeFileSync(file, yaml.dump(cell));
  const port = await freePort();
  const env = {
    ...process.env, DATA_DIR: dataDir, CELL_CONFIG: file, PORT: String(port), TLS_PORT: String(await freePort()), BFF_HOST: '127.0.0.1',
    ROSBRIDGE_PORT: String(rosbridgePort), ROS_MASTER_URI: 'http://127.0.0.1:1', PLANT_BROKER_URL: broker,
    PLANT_CELL_URL: `http://127.0.0.1:${port}/`, APP_DIR: path.join(dataDir, 'app'),
  };
  fs.mkdirSync(env.APP_DIR);
  fs.writeFileSync(path.join(env.APP_DIR, 'index.html'), '<!doctype html><title>shell</title>');
  const add = spawnSync(process.execPath, ['bff/src/cli/users.js', 'add', 'admin', '--role', 'admin', '--password-stdin'], { cwd: REPO_ROOT, env, input: 'plant-admin-pw', encoding: 'utf8' });
  assert.equal(add.status, 0, add.stderr);
  let log = '';
  const proc = spawn(process.execPath, ['bff/src/server.js'], { cwd: REPO_ROOT, env, stdio: ['ignore', 'pipe', 'pipe'] });
  proc.stdout.on('data', (d) => { log += d; });
  proc.stderr.on('data', (d) => { log += d; });
  cleanup.push(() => proc.kill('SIGKILL'));
  const base = `http://127.0.0.1:${port}`;
  await until(async () => (await fetch(`${base}/api/health`).catch(() => null))?.ok === true, 20_000, `${cellFile}'s BFF`);
  const res = await fetch(`${base}/api/auth/login`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ username: 'admin', password: 'plant-admin-pw' }) });
  assert.equal(res.status, 200);
  const cookie = (res.headers.get('set-cookie') || '').split(';')[0];
  return { proc, base, cookie, log: () => log, get: async (/** @type {string} */ p) => (await fetch(`${base}${p}`, { headers: { cookie } })).json() };
}

test('two cells report to a real broker: births, every change, a SIGKILLed BFF\'s death, a dead broker, a rebirth', { timeout: 90_000 }, async () => {
  const brokerPort = await freePort();
  let broker = await mosquitto(brokerPort);
  const url = `mqtt://127.0.0.1:${brokerPort}`;
  // The Sparkplug host of this test.
  /** @type {{type: string, node: string, seq: number | null, metrics: Record<string, any>}[]} */
  const seen = [];
  const host = mqtt.connect(url, { reconnectPeriod: 200 });
  cleanup.push(() => host.end(true));
  await new Promise((r) => host.once('connect', r));
  await host.subscribeAsync('spBv1.0/demo-plant/#');
  host.on('message', (topic, payload) => {
    const [, , type, node] = topic.split('/');
    if (!/^N(BIRTH|DATA|DEATH)$/.test(type)) return;
    const p = codec.decodePayload(payload);
    seen.push({ type, node, seq: p.seq == null ? null : Number(p.seq), metrics: Object.fromEntries((p.metrics || []).map((m) => [m.name, typeof m.value === 'object' && m.value !== null ? Number(m.value) : m.value])) });
  });
  const last = (/** @type {string} */ node, /** @type {string} */ type) => [...seen].reverse().find((m) => m.node === node && m.type === type);
  /** The value the host knows now: the latest birth, then every data after it. @param {string} node @param {string} name */
  const known = (node, name) => {
    let v;
    for (const m of seen) if (m.node === node && (m.type === 'NBIRTH' || m.type === 'NDATA') && name in m.metrics) v = m.metrics[name];
    return v;
  };

  const rbDemo = await rosbridge();
  const rbTwin = await rosbridge();
  const demo = await cellBff('config/demo-cell.yaml', rbDemo.port, url);
  const twin = await cellBff('config/twin-arm-cell.yaml', rbTwin.port, url);

  await until(() => Boolean(last('demo-ur5', 'NBIRTH') && last('twin-arm', 'NBIRTH')), 10_000, 'both births');
  const birth = /** @type {any} */ (last('twin-arm', 'NBIRTH'));
  assert.equal(birth.seq, 0);
  assert.equal(birth.metrics['Properties/Name'], 'Twin-arm hand-over cell');
  assert.equal(birth.metrics['Properties/URL'], `${twin.base}/`);
  assert.ok('Robot/left/Connected' in birth.metrics && 'Robot/right/Mode' in birth.metrics, Object.keys(birth.metrics).join());
  assert.equal(typeof birth.metrics.bdSeq, 'number');

  // Every change of the demo cell's state reaches the host (report by exception, rate-limited: the last value wins).
  await until(() => rbDemo.subscribed('/cell/alarms/status') && rbDemo.subscribed('/cell/mode') && rbDemo.subscribed('/cell/process/state'), 10_000, 'the demo BFF\'s subscriptions');
  await until(() => known('demo-ur5', 'ROS/Connected') === true, 5_000, 'ROS/Connected true');
  rbDemo.publish('/cell/mode', { mode: 'running', source: 'process', stamp: { secs: 0, nsecs: 0 } });
  await until(() => known('demo-ur5', 'Mode') === 'running', 5_000, 'Mode running');
  const t0 = Date.now();
  rbDemo.publish('/cell/alarms/status', { status: 'protective stop', text: 'Robot protective stop', active_count: 1, inactive_count: 0, highest_severity: 2 });
  await until(() => known('demo-ur5', 'Alarms/Active') === 1 && known('demo-ur5', 'Safety/Status') === 'protective stop', 5_000, 'the alarm');
  assert.ok(Date.now() - t0 < 1000, `the alarm took ${Date.now() - t0} ms`);
  rbDemo.publish('/cell/process/state', { state: 'running', operations: ['Pick', 'Place'], current: 1, cycles_done: 3, last_cycle_s: 7.5 });
  await until(() => known('demo-ur5', 'Process/Cycles done') === 3 && known('demo-ur5', 'Process/Operation') === 'Place' && known('demo-ur5', 'Process/Last cycle time') === 7.5, 5_000, 'the process');
  // seq goes up by one per message from the last birth on (a plant view coming online asks for a birth again).
  const ofDemo = seen.filter((m) => m.node === 'demo-ur5' && m.type !== 'NDEATH');
  const demoSeqs = ofDemo.slice(ofDemo.findLastIndex((m) => m.type === 'NBIRTH')).map((m) => m.seq);
  assert.ok(demoSeqs.length >= 4, `${demoSeqs.length} messages since the birth`);
  demoSeqs.forEach((s, i) => assert.equal(s, i === 0 ? 0 : (/** @type {number} */ (demoSeqs[i - 1]) + 1) % 256));
  // Nothing changed: nothing sent.
  const count = seen.length;
  rbDemo.publish('/cell/process/state', { state: 'running', operations: ['Pick', 'Place'], current: 1, cycles_done: 3, last_cycle_s: 7.5 });
  await new Promise((r) => setTimeout(r, 400)); // (the rate limit is 200 ms: an NDATA would be out by now)
  assert.equal(seen.length, count);

  // The demo cell's plant page sees both cells.
  const cells = (await demo.get('/api/plant/cells')).cells;
  assert.deepEqual(cells.map((/** @type {any} */ c) => c.node).sort(), ['demo-ur5', 'twin-arm']);
  const d = cells.find((/** @type {any} */ c) => c.node === 'demo-ur5');
  assert.deepEqual([d.online, d.alarms, d.safety, d.mode, d.cycles, d.url], [true, 1, 'protective stop', 'running', 3, `${demo.base}/`]);

  // SIGKILL of the twin cell's BFF: the broker publishes its NDEATH within 1.5 keep-alives.
  const killedAt = Date.now();
  twin.proc.kill('SIGKILL');
  await until(() => Boolean(last('twin-arm', 'NDEATH')), KEEPALIVE_S * 1500 + 2000, 'the twin cell\'s NDEATH');
  assert.equal(/** @type {any} */ (last('twin-arm', 'NDEATH')).metrics.bdSeq, birth.metrics.bdSeq);
  await until(async () => (await demo.get('/api/plant/cells')).cells.find((/** @type {any} */ c) => c.node === 'twin-arm')?.online === false, 2_000, 'the plant page to show the twin cell offline');
  assert.ok(Date.now() - killedAt <= KEEPALIVE_S * 1500 + 2000);

  // The cell's PC cut off (its connection half-open: the broker hears nothing, sees no close) and the cell started
  // again within the keep-alive: the old connection's will must not take the new session for dead. The new
  // connection takes the old one's session over (the same client id), so the broker sends the old will then, before
  // the new birth; and the new process's bdSeq is not the old one's.
  const twinBirths = () => seen.filter((m) => m.node === 'twin-arm' && m.type === 'NBIRTH').length;
  const before = twinBirths();
  const cut = await halfOpenProxy(brokerPort);
  const twin2 = await cellBff('config/twin-arm-cell.yaml', rbTwin.port, `mqtt://127.0.0.1:${cut.port}`);
  await until(() => twinBirths() > before, 10_000, 'the twin cell born again');
  cut.freeze();
  twin2.proc.kill('SIGKILL');
  const twin3 = await cellBff('config/twin-arm-cell.yaml', rbTwin.port, url);
  await until(() => twinBirths() > before + 1, 10_000, 'the restarted twin cell\'s birth');
  await new Promise((r) => setTimeout(r, KEEPALIVE_S * 1500 + 1000)); // past the killed process's keep-alive
  const view = (await demo.get('/api/plant/cells')).cells.find((/** @type {any} */ c) => c.node === 'twin-arm');
  assert.equal(view?.online, true, JSON.stringify(seen.filter((m) => m.node === 'twin-arm').map((m) => [m.type, m.metrics.bdSeq])));
  twin3.proc.kill('SIGKILL');

  // A dead broker: the cell's own API goes on, its System page says the link is down.
  broker.kill('SIGKILL');
  await until(async () => (await demo.get('/api/system')).health.plant.reporting.state === 'down', 10_000, 'the link shown down');
  assert.equal((await fetch(`${demo.base}/api/health`)).status, 200);
  assert.equal((await demo.get('/api/config')).cell.id, 'demo-ur5');
  assert.equal((await demo.get('/api/plant/cells')).broker.state, 'down');
  // Back: the cell is born again, with the next bdSeq and everything it knows.
  const births = seen.filter((m) => m.node === 'demo-ur5' && m.type === 'NBIRTH').length;
  broker = await mosquitto(brokerPort);
  await until(() => seen.filter((m) => m.node === 'demo-ur5' && m.type === 'NBIRTH').length > births, 40_000, 'the demo cell\'s rebirth');
  const again = /** @type {any} */ (last('demo-ur5', 'NBIRTH'));
  assert.notEqual(again.metrics.bdSeq, /** @type {any} */ (seen.find((m) => m.node === 'demo-ur5' && m.type === 'NBIRTH')).metrics.bdSeq);
  assert.deepEqual([again.metrics['Alarms/Active'], again.metrics.Mode], [1, 'running']);
  assert.match(demo.log(), /plant edge node demo-plant\/demo-ur5: broker mqtt:\/\/127\.0\.0\.1:\d+ down/);
  assert.equal(demo.log().match(/plant edge node demo-plant\/demo-ur5: broker \S+ down/g)?.length, 1, 'logged once per change');
});

test('a broker that refuses the cell\'s login: the System page says why, the cell goes on, the next try with the right password is born', { timeout: 60_000 }, async () => {
  const port = await freePort();
  const dir = tempDir('mosquitto-');
  // Readable after mosquitto drops root for its own user (it reads the password file then).
  fs.chmodSync(dir, 0o755);
  const pw = path.join(dir, 'passwords');
  fs.writeFileSync(pw, '', { mode: 0o644 });
  assert.equal(spawnSync('/usr/bin/mosquitto_passwd', ['-b', pw, 'cell-a', 'right-password']).status, 0);
  fs.writeFileSync(path.join(dir, 'm.conf'), `listener ${port} 127.0.0.1\nallow_anonymous false\npassword_file ${pw}\npersistence false\n`);
  const p = spawn('/usr/sbin/mosquitto', ['-c', path.join(dir, 'm.conf')], { stdio: 'ignore' });
  cleanup.push(() => p.kill('SIGKILL'));
  await until(() => reachable(port), 10_000, 'mosquitto');
  const { startBff, login } = await import('../helpers.js');
  const credentials = path.join(tempDir(), 'mqtt.cred');
  fs.writeFileSync(credentials, 'cell-a\nwrong-password\n');
  const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
  cell.plant.credentials_file = credentials;
  const file = path.join(tempDir(), 'cell.yaml');
  fs.writeFileSync(file, yaml.dump(cell));
  /** @type {string[]} */
  const logs = [];
  const t = await startBff({ CELL_CONFIG: file, PLANT_BROKER_URL: `mqtt://127.0.0.1:${port}` }, { log: (m) => logs.push(m) });
  cleanup.push(() => { t.stop(); });
  const admin = (await login(t.base, 'admin', t.passwords.admin)).cookie;
  const health = async () => (await (await fetch(`${t.base}/api/system`, { headers: { cookie: admin } })).json()).health.plant.reporting;
  await until(async () => /Not authorized/i.test((await health()).error), 10_000, 'the refusal on the System page');
  assert.equal((await health()).state, 'down');
  assert.equal((await fetch(`${t.base}/api/health`)).status, 200);
  // Several refused tries (back-off), one log line for the state.
  await new Promise((r) => setTimeout(r, 3500));
  assert.equal(logs.filter((m) => /plant edge node .* down/.test(m)).length, 1, logs.join('\n'));
  // The plant's admin fixes the broker's users: the cell's next try gets in, without a restart.
  assert.equal(spawnSync('/usr/bin/mosquitto_passwd', ['-b', pw, 'cell-a', 'wrong-password']).status, 0);
  p.kill('SIGHUP'); // mosquitto reloads its password file
  await until(async () => (await health()).state === 'connected', 40_000, 'the link up with the password the broker now takes');
});
