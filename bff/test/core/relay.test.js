// The /ros relay's transport: cookie authentication on upgrade, frames both ways, sockets closed on logout.
// A plain WebSocket server stands in for rosbridge here; the real one is exercised by the e2e suite.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { WebSocketServer, WebSocket } from 'ws';
import { encode as cborEncode, decode as cborDecode } from 'cbor-x';
import { startBff, login } from '../helpers.js';

let t; let upstream; let upstreamFrames;
before(async () => {
  upstreamFrames = [];
  upstream = new WebSocketServer({ port: 0, host: '127.0.0.1' });
  await new Promise((r) => upstream.on('listening', r));
  upstream.on('connection', (ws) => ws.on('message', (d, bin) => {
    upstreamFrames.push(d.toString());
    ws.send(JSON.stringify({ op: 'publish', topic: '/echo', msg: { data: d.toString() } }));
    if (bin) ws.send(d, { binary: true });
  }));
  t = await startBff({ ROSBRIDGE_PORT: String(upstream.address().port) });
});
after(async () => { await t.stop(); upstream.close(); });

const wsUrl = () => t.base.replace('http', 'ws') + '/ros';

function upgradeStatus(headers = {}) {
  return new Promise((resolve) => {
    const ws = new WebSocket(wsUrl(), { headers });
    ws.on('unexpected-response', (_req, res) => resolve(res.statusCode));
    ws.on('open', () => { ws.close(); resolve(101); });
    ws.on('error', () => {});
  });
}

function open(cookie) {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(wsUrl(), { headers: { cookie } });
    const inbox = [];
    ws.on('message', (d) => inbox.push(d.toString()));
    ws.on('open', () => resolve({ ws, inbox }));
    ws.on('error', reject);
  });
}

async function until(pred, ms = 3000) {
  const end = Date.now() + ms;
  while (!pred()) {
    if (Date.now() > end) throw new Error('timed out');
    await new Promise((r) => setTimeout(r, 20));
  }
}

test('no cookie or a bad token: the upgrade is refused with 401', async () => {
  assert.equal(await upgradeStatus(), 401);
  assert.equal(await upgradeStatus({ cookie: 'cell_session=not.a.jwt' }), 401);
});

test('a foreign Origin is refused with 403', async () => {
  const { cookie } = await login(t.base, 'operator', t.passwords.operator);
  assert.equal(await upgradeStatus({ cookie, origin: 'http://evil.example' }), 403);
});

test('frames are relayed both ways, binary stays binary', async () => {
  const { cookie } = await login(t.base, 'operator', t.passwords.operator);
  const { ws, inbox } = await open(cookie);
  ws.send(JSON.stringify({ op: 'subscribe', topic: '/cell/mode' }));
  await until(() => inbox.length >= 1);
  assert.ok(upstreamFrames.includes('{"op":"subscribe","topic":"/cell/mode"}'));
  assert.equal(JSON.parse(inbox[0]).msg.data, '{"op":"subscribe","topic":"/cell/mode"}');
  const bin = await new Promise((resolve) => {
    ws.once('message', () => ws.once('message', (d, isBinary) => resolve({ d, isBinary })));
    ws.send(cborEncode({ op: 'subscribe', topic: '/cell/wrench', id: 'c1' }), { binary: true });
  });
  assert.equal(bin.isBinary, true);
  assert.deepEqual(cborDecode(bin.d), { op: 'subscribe', topic: '/cell/wrench', id: 'c1' });
  ws.close();
});

test('logout closes the open socket and the old cookie no longer opens /ros', async () => {
  const { cookie } = await login(t.base, 'admin', t.passwords.admin);
  const { ws } = await open(cookie);
  const closed = new Promise((r) => ws.on('close', (code) => r(code)));
  await fetch(`${t.base}/api/auth/logout`, { method: 'POST', headers: { cookie } });
  assert.equal(await closed, 4001);
  assert.equal(await upgradeStatus({ cookie }), 401);
});

test('when rosbridge is down the upgrade is refused with 502, and the BFF keeps serving', async () => {
  const dead = await startBff({ ROSBRIDGE_PORT: '1' });
  try {
    const { cookie } = await login(dead.base, 'operator', dead.passwords.operator);
    const ws = new WebSocket(dead.base.replace('http', 'ws') + '/ros', { headers: { cookie } });
    ws.on('error', () => {});
    const status = await new Promise((r) => ws.on('unexpected-response', (_q, res) => r(res.statusCode)));
    assert.equal(status, 502);
    assert.equal((await fetch(`${dead.base}/api/health`)).status, 200);
  } finally {
    await dead.stop();
  }
});

test('when rosbridge goes away the browser socket closes', async () => {
  const { cookie } = await login(t.base, 'operator', t.passwords.operator);
  const { ws } = await open(cookie);
  const closed = new Promise((r) => ws.on('close', (code) => r(code)));
  for (const c of upstream.clients) c.terminate();
  assert.equal(await closed, 1012);
});

test('a denied op is answered with a rosbridge error and never reaches rosbridge', async () => {
  const { cookie } = await login(t.base, 'operator', t.passwords.operator);
  const { ws, inbox } = await open(cookie);
  const before = upstreamFrames.length;
  ws.send(JSON.stringify({ op: 'publish', id: 'p9', topic: '/cell/mode', msg: { mode: 'running' } }));
  ws.send(JSON.stringify({ op: 'call_service', id: 'c9', service: '/cell/set_mode', args: {} }));
  ws.send('{"op": "subscribe", "topic": ');
  ws.send(cborEncode({ op: 'advertise', id: 'a9', topic: '/x', type: 'std_msgs/String' }), { binary: true });
  await until(() => inbox.length >= 5);
  const got = inbox.map((m) => JSON.parse(m));
  assert.deepEqual(got.map((m) => [m.op, m.id, m.level ?? m.result]), [
    ['status', 'p9', 'error'], ['status', 'c9', 'error'], ['service_response', 'c9', false], ['status', undefined, 'error'], ['status', 'a9', 'error'],
  ]);
  assert.match(got[0].msg, /permission denied: publish \(id p9\): not allowed to publish \/cell\/mode/);
  assert.match(got[3].msg, /cannot decode the JSON frame/);
  assert.equal(upstreamFrames.length, before, 'nothing was forwarded');
  ws.close();
});

test('removing the user closes the open socket', async () => {
  await t.bff.users.add('gone', 'operator', 'gone-password');
  const { cookie } = await login(t.base, 'gone', 'gone-password');
  const { ws } = await open(cookie);
  const closed = new Promise((r) => ws.on('close', (code) => r(code)));
  t.bff.users.remove('gone');
  assert.equal(await closed, 4001);
});

test('motion ops pass only for the session holding the control lease', async () => {
  const { cookie } = await login(t.base, 'admin', t.passwords.admin);
  const { ws, inbox } = await open(cookie);
  const jog = { op: 'publish', id: 'j1', topic: '/cell/manual/jog', msg: { data: 1 } };
  ws.send(JSON.stringify(jog));
  await until(() => inbox.some((m) => JSON.parse(m).id === 'j1'));
  assert.match(JSON.parse(inbox.find((m) => JSON.parse(m).id === 'j1')).msg, /needs control: take control first/);
  assert.ok(!upstreamFrames.includes(JSON.stringify(jog)));

  const take = await fetch(`${t.base}/api/control/take`, { method: 'POST', headers: { cookie } });
  assert.equal(take.status, 200);
  const jog2 = { ...jog, id: 'j2' };
  ws.send(JSON.stringify(jog2));
  const j2 = (/** @type {string} */ f) => f.startsWith('{') && JSON.parse(f).id === 'j2'; // (CBOR frames of other tests too)
  await until(() => upstreamFrames.some(j2));
  const passed = JSON.parse(upstreamFrames.find(j2));
  assert.deepEqual({ ...passed, msg: { ...passed.msg, stamp: undefined } }, { ...jog2, msg: { ...jog2.msg, stamp: undefined } });
  assert.ok(Math.abs(passed.msg.stamp.secs - Date.now() / 1000) < 5, 'stamped as it passed (the driver drops late heartbeats)');

  // Another admin session sees the holder named, until it takes over.
  const other = await login(t.base, 'admin', t.passwords.admin);
  const o = await open(other.cookie);
  o.ws.send(JSON.stringify({ ...jog, id: 'j3' }));
  await until(() => o.inbox.some((m) => JSON.parse(m).id === 'j3'));
  assert.match(JSON.parse(o.inbox.find((m) => JSON.parse(m).id === 'j3')).msg, /which admin holds/);

  // Closing the holder's only socket gives control back.
  const closed = new Promise((r) => ws.on('close', r));
  ws.close();
  await closed;
  await until(() => t.bff.lease.describe() === null);
  o.ws.close();
});
