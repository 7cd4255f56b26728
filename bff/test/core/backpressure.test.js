// Back-pressure in the /ros relay: the queueing policy on its own (ros/outbox.js), then the relay with a browser
// that stops reading (its socket paused), against a stand-in rosbridge that streams 30 KB CBOR frames.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import http from 'node:http';
import { WebSocketServer, WebSocket } from 'ws';
import { encode as cborEncode, decode as cborDecode } from 'cbor-x';
import { ClientOutbox, SendWindow, classify, DEFAULTS } from '../../src/core/ros/outbox.js';
import { RosRelay } from '../../src/core/ros/relay.js';

const pub = (topic, n, size = 10) => Buffer.from(JSON.stringify({ op: 'publish', topic, msg: { n, pad: 'x'.repeat(size) } }));
const reply = (id, size = 10) => Buffer.from(JSON.stringify({ op: 'service_response', service: '/s', id, values: { pad: 'y'.repeat(size) }, result: true }));
const drain = (ob) => { const out = []; for (let f = ob.shift(); f; f = ob.shift()) out.push(JSON.parse(f.data.toString())); return out; };

test('classify reads op and topic from the head of JSON and CBOR frames, and decodes odd shapes', () => {
  assert.deepEqual(classify(pub('/cam', 1), false), { op: 'publish', topic: '/cam' });
  assert.deepEqual(classify(reply('a'), false), { op: 'service_response', topic: undefined });
  assert.deepEqual(classify(Buffer.from('{"msg":{"topic":"/inner"},"topic":"/outer","op":"publish"}'), false), { op: 'publish', topic: '/outer' });
  assert.deepEqual(classify(Buffer.from(cborEncode({ op: 'publish', topic: '/cam', msg: { data: Buffer.alloc(30000) } })), true), { op: 'publish', topic: '/cam' });
  assert.deepEqual(classify(Buffer.from(cborEncode({ msg: { data: Buffer.alloc(300) }, topic: '/late', op: 'publish' })), true), { op: 'publish', topic: '/late' });
  assert.equal(classify(Buffer.from(cborEncode({ op: 'service_response', id: 'x', values: {}, result: true })), true).op, 'service_response');
  assert.deepEqual(classify(Buffer.from('not json'), false), {});
});

test('outbox: per topic the newest message replaces an older unsent one (queue_length, default 1)', () => {
  const ob = new ClientOutbox();
  ob.noteRequest({ op: 'subscribe', id: 's1', topic: '/cam', queue_length: 0 });
  ob.noteRequest({ op: 'subscribe', id: 's2', topic: '/joints', queue_length: 3 });
  for (let n = 0; n < 10; n++) { ob.push(pub('/cam', n), false); ob.push(pub('/joints', n), false); }
  ob.push(pub('/unknown', 1), false);
  ob.push(pub('/unknown', 2), false);
  assert.deepEqual(drain(ob).map((m) => [m.topic, m.msg.n]), [['/joints', 7], ['/joints', 8], ['/cam', 9], ['/joints', 9], ['/unknown', 2]]);
  assert.equal(ob.dropped, 9 + 7 + 1);
  assert.equal(ob.queuedBytes, 0);
  // The largest queue_length of a topic's subscriptions wins; unsubscribing one id keeps the others'.
  ob.noteRequest({ op: 'subscribe', id: 's3', topic: '/joints', queue_length: 5 });
  assert.equal(ob.queueLengthOf('/joints'), 5);
  ob.noteRequest({ op: 'unsubscribe', id: 's3', topic: '/joints' });
  assert.equal(ob.queueLengthOf('/joints'), 3);
  ob.noteRequest({ op: 'subscribe', id: 'big', topic: '/x', queue_length: 1e9 });
  assert.equal(ob.queueLengthOf('/x'), 100, 'capped at maxQueueLength');
  // JSON and CBOR encodings of one topic are separate lanes.
  ob.push(pub('/cam', 1), false);
  ob.push(Buffer.from(cborEncode({ op: 'publish', topic: '/cam', msg: { n: 2 } })), true);
  assert.equal(ob.length, 2);
});

test('outbox: replies are never dropped, keep their order among messages, and report when past the bound', () => {
  const ob = new ClientOutbox({ maxReplyBytes: 2000 });
  assert.equal(ob.push(reply('a'), false), true);
  ob.push(pub('/cam', 1), false);
  ob.push(reply('b'), false);
  ob.push(pub('/cam', 2), false);
  ob.push(reply('c'), false);
  assert.deepEqual(drain(ob).map((m) => m.id ?? m.msg.n), ['a', 'b', 2, 'c']);
  let ok = true;
  for (let i = 0; i < 30 && ok; i++) ok = ob.push(reply(`r${i}`, 100), false);
  assert.equal(ok, false, 'past maxReplyBytes push says so');
  assert.ok(ob.replyBytes > 2000);
  assert.equal(drain(ob).length, ob.seq - 5, 'every reply is still there');
});

test('send window: closes after windowBytes unconfirmed, a ping always follows the last write, its pong reopens it', () => {
  const w = new SendWindow({ windowBytes: 64_000, pingEveryBytes: 16_000, pingEveryMs: 0 });
  const pings = [];
  while (w.open()) { const p = w.wrote(30_000); if (p) pings.push(p); }
  assert.equal(w.sentBytes, 90_000);
  assert.equal(pings.length, 3);
  assert.equal(w.pong('someone else'), false);
  assert.equal(w.pong(pings[0]), true);
  assert.equal(w.unacked, 60_000);
  assert.equal(w.open(), true);
  w.pong(pings[2]);
  assert.equal(w.unacked, 0);
  assert.equal(w.pings.size, 0);
});

test('send window: on a fast link a ping per window, not per frame; a pong that confirms old bytes is no fast-link sample', () => {
  let t = 0;
  const w = new SendWindow({ windowBytes: 64_000, pingEveryBytes: 16_000, pingEveryMs: 100 }, () => t);
  const pings = [];
  for (let i = 0; i < 30; i++) {   // 30 Hz x 30 KB, each pong back 1 ms after its ping
    t = i * 33;
    const p = w.wrote(30_000);
    if (p) { pings.push(p); t += 1; w.pong(p); }
  }
  assert.ok(pings.length <= 15 && pings.length >= 8, `${pings.length} pings for 30 frames`);
  assert.equal(w.unacked <= 64_000, true);
  // frames written over 66 ms confirmed by a pong 1 ms after its ping: read over those 66 ms, not 1 ms
  const later = w.rates.slice(1).map((r) => r.rate);
  assert.ok(later.length > 0 && Math.max(...later) < 2 * 30_000 / 33, `rate samples ${later} bytes/ms`);
  assert.equal(w.windowBytes, 64_000);
});

// --- the relay with a stand-in rosbridge ---

const FRAME = 30 * 1024;
let upstream; let server; let relay; let logs; let base;
before(async () => {
  upstream = new WebSocketServer({ port: 0, host: '127.0.0.1' });
  await new Promise((r) => upstream.on('listening', r));
  upstream.on('connection', (ws) => {
    /** @type {NodeJS.Timeout[]} */
    const timers = [];
    ws.on('message', (d) => {
      const m = JSON.parse(d.toString());
      if (m.op === 'subscribe') {
        let n = 0;
        timers.push(setInterval(() => ws.send(cborEncode({ op: 'publish', topic: m.topic, msg: { n: n++, stamp: Date.now(), data: Buffer.alloc(FRAME) } }), { binary: true }), 10));
      } else if (m.op === 'call_service') {
        ws.send(JSON.stringify({ op: 'service_response', service: m.service, id: m.id, values: { pad: 'z'.repeat(m.args.size) }, result: true }));
      }
    });
    ws.on('close', () => timers.forEach(clearInterval));
  });
  logs = [];
  relay = new RosRelay({
    upstreamUrl: `ws://127.0.0.1:${upstream.address().port}`,
    authenticate: () => ({ username: 'phone', role: 'operator', sid: 's', claims: /** @type {any} */ ({}) }),
    guard: { inspect: (_c, data) => ({ forward: true, data, replies: [], msg: JSON.parse(data.toString()) }), outbound: (_c, d) => d },
    flow: { maxReplyBytes: 512 * 1024 },
    log: (m) => logs.push(m),
  });
  server = http.createServer();
  server.on('upgrade', (req, socket, head) => relay.handleUpgrade(req, socket, head));
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  base = `ws://127.0.0.1:${server.address().port}/ros`;
});
after(async () => { relay.close(); server.closeAllConnections(); await new Promise((r) => server.close(r)); upstream.close(); });

function open() {
  return new Promise((resolve, reject) => {
    const ws = new WebSocket(base);
    /** @type {{m: any, at: number}[]} */
    const inbox = [];
    ws.on('message', (d, bin) => inbox.push({ m: bin ? cborDecode(d) : JSON.parse(d.toString()), at: Date.now() }));
    ws.on('open', () => resolve({ ws, inbox }));
    ws.on('error', reject);
  });
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const statsOf = () => relay.flowStats()[0];

test('a browser that stops reading costs bounded queued bytes and gets a fresh frame first after the stale in-flight ones', async () => {
  const { ws, inbox } = await open();
  ws.send(JSON.stringify({ op: 'subscribe', id: 's1', topic: '/cam', compression: 'cbor' }));
  await sleep(300);
  assert.ok(inbox.length > 10, 'frames flow while it reads');
  /** @type {any} */ (ws)._socket.pause();
  const pausedAt = Date.now();
  let peakUnacked = 0; let peakBuffered = 0;
  for (let i = 0; i < 20; i++) {
    await sleep(100);
    const s = statsOf();
    peakUnacked = Math.max(peakUnacked, s.unacked);
    for (const c of relay.clients.keys()) peakBuffered = Math.max(peakBuffered, c.bufferedAmount);
  }
  const s = statsOf();
  // 2 s at 100 Hz x 30 KB = 6 MB offered; the relay holds one frame and a window's worth on the wire.
  assert.ok(s.peakQueuedBytes <= 2 * (FRAME + 100), `queued at most two frames (peak ${s.peakQueuedBytes})`);
  assert.ok(peakUnacked <= DEFAULTS.windowBytes + FRAME + 100, `unconfirmed bytes bounded by the window (${peakUnacked})`);
  assert.ok(peakBuffered <= DEFAULTS.windowBytes + FRAME + 100, `ws bufferedAmount bounded (${peakBuffered})`);
  assert.ok(s.dropped > 150, `older unsent frames were replaced (${s.dropped})`);
  const before = inbox.length;
  /** @type {any} */ (ws)._socket.resume();
  const resumedAt = Date.now();
  await sleep(500);
  const after = inbox.slice(before);
  const stale = after.filter((x) => x.m.msg.stamp < pausedAt + 50);
  const fresh = after.find((x) => x.m.msg.stamp >= pausedAt + 50);
  assert.ok(stale.length * FRAME <= DEFAULTS.windowBytes + 2 * FRAME, `only what was on the wire at the stall arrives stale (${stale.length})`);
  assert.ok(fresh, 'a frame written after the stall arrives');
  assert.ok(fresh.m.msg.stamp >= resumedAt - 100, `the first frame after the stall is fresh (${resumedAt - fresh.m.msg.stamp} ms before resume)`);
  assert.ok(fresh.at - fresh.m.msg.stamp < 500, 'and young on arrival');
  ws.close();
  await sleep(50);
});

test('service responses are never dropped under back-pressure; past the reply bound the client is disconnected with a logged reason', async () => {
  const { ws, inbox } = await open();
  ws.send(JSON.stringify({ op: 'subscribe', id: 's1', topic: '/cam', compression: 'cbor' }));
  await sleep(200);
  /** @type {any} */ (ws)._socket.pause();
  for (let i = 0; i < 40; i++) {
    ws.send(JSON.stringify({ op: 'call_service', id: `c${i}`, service: '/cell/s', args: { size: 4000 } }));
    await sleep(10);
  }
  await sleep(300);
  const s = statsOf();
  assert.ok(s.dropped > 20, 'image frames were dropped meanwhile');
  assert.ok(s.replyBytes > 0, 'replies wait in the outbox');
  /** @type {any} */ (ws)._socket.resume();
  await sleep(500);
  const ids = inbox.filter((x) => x.m.op === 'service_response').map((x) => x.m.id);
  assert.deepEqual(ids, Array.from({ length: 40 }, (_, i) => `c${i}`), 'every response, in order');
  assert.ok(inbox.slice(-5).some((x) => x.m.op === 'publish'), 'images flow again');

  // Now beyond the bound (512 KB of replies in this relay): the client is cut off and the reason logged.
  /** @type {any} */ (ws)._socket.pause();
  const closed = new Promise((r) => ws.on('close', r));
  for (let i = 0; i < 40; i++) ws.send(JSON.stringify({ op: 'call_service', id: `d${i}`, service: '/cell/s', args: { size: 50_000 } }));
  await sleep(500);
  assert.equal(relay.clients.size, 0, 'the relay let go of the client');
  assert.ok(logs.some((l) => /closing \/ros of phone: not reading \(\d+ bytes of replies unsent, limit 524288\)/.test(l)), logs.join('\n'));
  /** @type {any} */ (ws)._socket.resume();
  await closed;
});

test('a fast client beside a stalled one gets every message', async () => {
  const slow = await open();
  const fast = await open();
  slow.ws.send(JSON.stringify({ op: 'subscribe', id: 's', topic: '/cam', compression: 'cbor' }));
  fast.ws.send(JSON.stringify({ op: 'subscribe', id: 'f', topic: '/cam', compression: 'cbor' }));
  await sleep(200);
  /** @type {any} */ (slow.ws)._socket.pause();
  const from = fast.inbox.length;
  await sleep(1000);
  const ns = fast.inbox.slice(from).map((x) => x.m.msg.n);
  assert.ok(ns.length >= 50, `fast client kept receiving (${ns.length})`);
  assert.deepEqual(ns, Array.from({ length: ns.length }, (_, i) => ns[0] + i), 'no gaps');
  /** @type {any} */ (slow.ws)._socket.resume();
  slow.ws.close(); fast.ws.close();
  await sleep(50);
});
