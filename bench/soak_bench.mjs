#!/usr/bin/env node
// Soak (issue 15, `npm run bench -- --soak`): many clients at a steady rate through the BFF's /ros relay for
// minutes, watching the memory of the BFF and of our rosbridge server. Starts its own stack (scripts/stack.js,
// UR_SIM=0, ports 29080-29083, UR_HOST 127.0.0.41) with an admin user, stops it at the end or on Ctrl-C.
//
// Each client logs in on its own (own session cookie) and opens /ros. Client i advertises /soak/c<i>
// (std_msgs/String "<seq> <send time>"), publishes it at --rate Hz and subscribes to /soak/c<i+1 mod n>
// (queue_length 10), so every message goes BFF -> rosbridge -> ROS (TCPROS) -> rosbridge -> BFF -> a client.
// Once a second each client calls a service, /cell/get_mode and /rosapi/topics in turn (the second one goes
// through the BFF's rosapi filter). Once a minute each client GETs /api/auth/me, as the app does, and keeps a
// renewed cookie. A closed socket is reopened after 1 s (logging in again if the cookie is refused).
//
// Every minute: RSS of the BFF and of the rosbridge server (median of samples every 5 s in that minute, from
// /proc/<pid>/status VmRSS), their CPU, messages sent/received, loss (sequence gaps), latency p50/p99
// (receipt - send, one clock), service calls, errors and status messages, reconnects.
// Verdict: RSS flat within 10 %: after a 1-minute warm-up, max/min of the per-minute RSS values (minutes 2..N)
// <= 1.10, for each process; exit 1 on FAIL.
// Options: --minutes N (10), --clients N (25), --rate HZ (100), --json FILE (also written to
// bench/results/soak-<date>.json when bench/results exists).
// BENCH_QUICK=1 (npm run bench -- --quick [soak]): 3 "minutes" of 8 s each (SOAK_MINUTE_MS, --minutes still win),
// the same figures for a quick look; the RSS verdict over windows that short is indicative only (no exit 1 for it;
// a restart still fails), and the JSON goes to bench/results/soak-quick-<date>.json, never over the full run's.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { WebSocket } from 'ws';
import { stackEnv, addUser, startStack, stopStack, pidsOfStack, REPO_ROOT } from '../e2e/lib/stack.js';

const args = process.argv.slice(2);
const opt = (name, dflt) => { const i = args.indexOf(`--${name}`); return i >= 0 && i + 1 < args.length ? args[i + 1] : dflt; };
const QUICK = process.env.BENCH_QUICK === '1';
const MINUTES = Number(opt('minutes', QUICK ? 3 : 10));
const CLIENTS = Number(opt('clients', 25));
const RATE = Number(opt('rate', 100));
const JSON_OUT = opt('json', null);
for (const [k, v] of [['minutes', MINUTES], ['clients', CLIENTS], ['rate', RATE]]) {
  if (!Number.isFinite(v) || v <= 0 || (k !== 'rate' && !Number.isInteger(v))) { console.error(`--${k}: a positive number please (got ${v})`); process.exit(2); }
}
const MINUTE_MS = Number(process.env.SOAK_MINUTE_MS || (QUICK ? 8_000 : 60_000)); // shorter: quick mode, or to test the bench itself
const SAMPLE_MS = Math.min(5000, MINUTE_MS / 4);
const SERVICES = ['/cell/get_mode', '/rosapi/topics'];
const SERVICE_TIMEOUT_MS = 5000;
const FLAT = 1.10;
const PORT = 29080;
const USER = 'soak';
const PASSWORD = 'soak-password';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const now = () => performance.now();
const mib = (kb) => kb / 1024;
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s.length ? (s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2) : NaN; };
/** Least-squares slope of ys against 0..n-1 (per step). @param {number[]} ys */
const slope = (ys) => { const n = ys.length; if (n < 2) return NaN; const mx = (n - 1) / 2; const my = ys.reduce((a, b) => a + b, 0) / n; let sxy = 0; let sxx = 0; ys.forEach((y, x) => { sxy += (x - mx) * (y - my); sxx += (x - mx) ** 2; }); return sxy / sxx; };
const rssKb = (pid) => { try { return Number(/VmRSS:\s+(\d+)/.exec(fs.readFileSync(`/proc/${pid}/status`, 'utf8'))[1]); } catch { return NaN; } };
const cpuTicks = (pid) => { try { const f = fs.readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' '); return Number(f[11]) + Number(f[12]); } catch { return NaN; } };
/** [busy, total] jiffies of the whole host (all cores) */
const hostTicks = () => { const f = fs.readFileSync('/proc/stat', 'utf8').split('\n')[0].trim().split(/\s+/).slice(1).map(Number); const tot = f.reduce((a, b) => a + b, 0); return [tot - f[3] - (f[4] || 0), tot]; };
const cmdline = (pid) => { try { return fs.readFileSync(`/proc/${pid}/cmdline`, 'utf8').split('\0').join(' '); } catch { return ''; } };

/** Latency histogram: 0.05 ms buckets up to 10 s (the last bucket holds everything above). */
class Hist {
  constructor() { this.b = new Uint32Array(200_001); this.n = 0; this.max = 0; }
  add(ms) { const i = Math.min(this.b.length - 1, Math.max(0, Math.round(ms * 20))); this.b[i]++; this.n++; if (ms > this.max) this.max = ms; }
  merge(h) { for (let i = 0; i < this.b.length; i++) this.b[i] += h.b[i]; this.n += h.n; this.max = Math.max(this.max, h.max); }
  pct(p) {
    if (!this.n) return NaN;
    const want = Math.ceil((p / 100) * this.n);
    let acc = 0;
    for (let i = 0; i < this.b.length; i++) { acc += this.b[i]; if (acc >= want) return i / 20; }
    return this.max;
  }
}

const newWindow = () => ({ sent: 0, received: 0, perClient: new Uint32Array(CLIENTS), lost: 0, reordered: 0, lat: new Hist(), svcOk: 0, svcFail: 0, svcTimeout: 0,
  svcLat: new Hist(), status: 0, wsErrors: 0, closes: 0, reconnects: 0, skippedTicks: 0 });
let win = newWindow();
const total = newWindow();
/** Odd things, grouped by kind (client number and call ids left out): kind -> count, first and last time, clients. */
const notes = new Map();
const note = (s) => {
  const t = new Date().toISOString().slice(11, 19);
  const who = /^client (\d+): /.exec(s);
  const kind = s.replace(/^client \d+: /, '').replace(/svc\d+_\d+/g, 'svc<n>');
  const e = notes.get(kind) || { count: 0, first: t, last: t, clients: new Set() };
  e.count++; e.last = t;
  if (who) e.clients.add(Number(who[1]));
  if (notes.size < 200 || notes.has(kind)) notes.set(kind, e);
};

// ---- the stack ----
const env = stackEnv({ port: PORT, masterPort: PORT + 1, rosbridgePort: PORT + 2, urHost: '127.0.0.41', extraEnv: { UR_SIM: '0' } });
addUser(env, USER, 'admin', PASSWORD);
const base = `http://127.0.0.1:${PORT}`;
let stack = null;
let stopping = false;
/** @type {Client[]} */
const clients = [];

async function shutdown(code, why) {
  if (stopping) return;
  stopping = true;
  if (why) console.log(why);
  for (const c of clients) c.close();
  if (stack) {
    const s = await stopStack(stack.proc);
    console.log(`stack stopped in ${s.toFixed(1)} s`);
  }
  if (code === 0) fs.rmSync(env.DATA_DIR, { recursive: true, force: true });
  else console.log(`stack log and data kept in ${env.DATA_DIR}`);
  process.exit(code);
}
let interrupted = false;
for (const sig of ['SIGINT', 'SIGTERM', 'SIGHUP']) process.on(sig, () => { interrupted = true; });

async function login() {
  const r = await fetch(`${base}/api/auth/login`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ username: USER, password: PASSWORD }) });
  if (!r.ok) throw new Error(`login: HTTP ${r.status} ${await r.text()}`);
  return String(r.headers.get('set-cookie')).split(';')[0];
}

class Client {
  /** @param {number} i */
  constructor(i) {
    this.i = i;
    this.topic = `/soak/c${i}`;
    this.peerTopic = `/soak/c${(i + 1) % CLIENTS}`;
    this.cookie = '';
    /** @type {WebSocket|null} */
    this.ws = null;
    this.ready = false;
    this.seq = 0;
    this.lastPeerSeq = -1;
    this.svcN = 0;
    /** @type {Map<string, {t: number, service: string}>} */
    this.pending = new Map();
    this.closed = false;
    this.timer = null;
  }

  async open() {
    if (!this.cookie) this.cookie = await login();
    await new Promise((resolve, reject) => {
      const ws = new WebSocket(`ws://127.0.0.1:${PORT}/ros`, { headers: { cookie: this.cookie }, perMessageDeflate: false });
      this.ws = ws;
      ws.once('unexpected-response', (req, res) => {
        res.resume();
        req.destroy();
        if (res.statusCode === 401) this.cookie = '';
        reject(new Error(`/ros upgrade refused: HTTP ${res.statusCode}`));
      });
      ws.once('open', () => {
        ws.send(JSON.stringify({ op: 'advertise', id: `adv${this.i}`, topic: this.topic, type: 'std_msgs/String' }));
        ws.send(JSON.stringify({ op: 'subscribe', id: `sub${this.i}`, topic: this.peerTopic, type: 'std_msgs/String', queue_length: 10 }));
        this.ready = true;
        resolve();
      });
      ws.on('message', (d, isBinary) => this.onMessage(d, isBinary));
      ws.on('error', (e) => { win.wsErrors++; note(`client ${this.i}: socket error ${e.message}`); reject(e); });
      ws.on('close', (code, reason) => {
        const was = this.ready;
        this.ready = false;
        if (this.ws !== ws || this.closed || stopping || interrupted) return;
        if (was) { win.closes++; note(`client ${this.i}: /ros closed ${code} ${reason.toString()}`); }
        this.reconnectSoon();
      });
    });
  }

  reconnectSoon() {
    if (this.timer || this.closed) return;
    this.timer = setTimeout(async () => {
      this.timer = null;
      if (this.closed || stopping) return;
      try {
        await this.open();
        win.reconnects++;
      } catch (e) {
        note(`client ${this.i}: reconnect failed: ${e.message}`);
        this.reconnectSoon();
      }
    }, 1000);
  }

  /** @param {Buffer} d @param {boolean} isBinary */
  onMessage(d, isBinary) {
    const t = now();
    if (isBinary) { note(`client ${this.i}: unexpected binary frame`); return; }
    let m;
    try { m = JSON.parse(d.toString()); } catch { win.status++; note(`client ${this.i}: undecodable frame`); return; }
    if (m.op === 'publish' && m.topic === this.peerTopic) {
      const [seqS, tS] = String(m.msg?.data).split(' ');
      const seq = Number(seqS);
      win.received++;
      win.perClient[this.i]++;
      win.lat.add(t - Number(tS));
      if (this.lastPeerSeq >= 0) {
        if (seq > this.lastPeerSeq + 1) win.lost += seq - this.lastPeerSeq - 1;
        else if (seq <= this.lastPeerSeq) win.reordered++;
      }
      if (seq > this.lastPeerSeq) this.lastPeerSeq = seq;
    } else if (m.op === 'service_response') {
      const p = this.pending.get(m.id);
      if (!p) { note(`client ${this.i}: answer to an unknown or timed-out call ${m.id} after all`); return; }
      this.pending.delete(m.id);
      if (m.result) { win.svcOk++; win.svcLat.add(t - p.t); } else { win.svcFail++; note(`client ${this.i}: ${m.service} failed: ${JSON.stringify(m.values).slice(0, 160)}`); }
    } else if (m.op === 'status') {
      win.status++;
      note(`client ${this.i}: status ${m.level}: ${String(m.msg).slice(0, 160)}`);
    } else {
      note(`client ${this.i}: unexpected op ${m.op} ${m.topic || ''}`);
    }
  }

  publish() {
    if (!this.ready || this.ws?.readyState !== WebSocket.OPEN) return;
    this.ws.send(JSON.stringify({ op: 'publish', topic: this.topic, msg: { data: `${this.seq++} ${now().toFixed(3)}` } }));
    win.sent++;
  }

  callService() {
    const t = now();
    for (const [id, p] of this.pending) if (t - p.t > SERVICE_TIMEOUT_MS) { this.pending.delete(id); win.svcTimeout++; note(`client ${this.i}: ${p.service} call ${id} unanswered after ${SERVICE_TIMEOUT_MS} ms`); }
    if (!this.ready || this.ws?.readyState !== WebSocket.OPEN) return;
    const service = SERVICES[this.svcN % SERVICES.length];
    const id = `svc${this.i}_${this.svcN++}`;
    this.pending.set(id, { t, service });
    this.ws.send(JSON.stringify({ op: 'call_service', id, service, args: {} }));
  }

  /** GET /api/auth/me as the app does; keep a renewed cookie. */
  async touch() {
    try {
      const r = await fetch(`${base}/api/auth/me`, { headers: { cookie: this.cookie } });
      const set = r.headers.get('set-cookie');
      if (set) this.cookie = set.split(';')[0];
      if (!r.ok) { win.status++; note(`client ${this.i}: /api/auth/me HTTP ${r.status}`); }
      await r.arrayBuffer();
    } catch (e) { win.wsErrors++; note(`client ${this.i}: /api/auth/me ${e.message}`); }
  }

  close() {
    this.closed = true;
    if (this.timer) clearTimeout(this.timer);
    try { this.ws?.close(); } catch { /* gone */ }
  }
}

/** Drift-free ticks at `hz`, phase-shifted; a tick more than 2 periods late is skipped (counted), never bunched. */
function ticker(hz, phaseMs, fn) {
  const period = 1000 / hz;
  const t0 = now() + phaseMs;
  let k = 0;
  let timer;
  const step = () => {
    if (stopping || interrupted) return;
    const late = now() - (t0 + k * period);
    if (late > 2 * period) { const skip = Math.floor(late / period); win.skippedTicks += skip; k += skip; }
    fn();
    k++;
    timer = setTimeout(step, Math.max(0, t0 + k * period - now()));
  };
  timer = setTimeout(step, Math.max(0, phaseMs));
  return () => clearTimeout(timer);
}

function findPids() {
  const pids = pidsOfStack(env.DATA_DIR);
  const bff = pids.find((p) => cmdline(p).includes('bff/src/server.js'));
  const rosbridge = pids.find((p) => /python/.test(cmdline(p)) && cmdline(p).includes('rosbridge_server'));
  return { bff, rosbridge };
}

const f1 = (x) => (Number.isFinite(x) ? x.toFixed(1) : '-');
const f2 = (x) => (Number.isFinite(x) ? x.toFixed(2) : '-');
const COLS = [
  ['min', 4], ['BFF MiB', 8], ['rb MiB', 7], ['BFF CPU%', 8], ['rb CPU%', 7], ['bench CPU%', 10], ['host busy%', 10], ['sent', 7], ['received', 8], ['rx/s', 6],
  ['lost', 5], ['silent', 6], ['p50 ms', 7], ['p99 ms', 7], ['svc ok/fail/to', 14], ['svc p99', 7], ['status+err', 10], ['reconn', 6],
];
const header = () => COLS.map(([h, w]) => h.padStart(w)).join(' | ');
const row = (r) => [
  r.minute, f1(r.bffRssMiB), f1(r.rosbridgeRssMiB), f1(r.bffCpuPct), f1(r.rosbridgeCpuPct), f1(r.benchCpuPct), f1(r.hostBusyPct), r.sent, r.received, f1(r.receivedPerS),
  r.lost, r.silentClients, f2(r.p50Ms), f2(r.p99Ms), `${r.svcOk}/${r.svcFail}/${r.svcTimeout}`, f2(r.svcP99Ms), r.status + r.wsErrors, r.reconnects,
].map((v, k) => String(v).padStart(COLS[k][1])).join(' | ');

async function main() {
  const date = new Date().toISOString();
  console.log(`Soak: ${CLIENTS} clients x ${RATE} Hz through the BFF's /ros for ${MINUTES} min${MINUTE_MS !== 60_000 ? ` of ${MINUTE_MS / 1000} s each${QUICK ? ', quick' : ''}` : ''} (${date.slice(0, 16)}Z, ${os.cpus().length} cores, load ${os.loadavg().map((l) => l.toFixed(1)).join(' ')})`);
  console.log(`starting the stack (UR_SIM=0, BFF on ${PORT}, rosbridge on ${PORT + 2}, DATA_DIR ${env.DATA_DIR}) ...`);
  stack = await startStack(env);
  if (interrupted) return shutdown(130, 'interrupted');
  let pids = findPids();
  if (!pids.bff || !pids.rosbridge) throw new Error(`cannot find the processes of this stack: BFF ${pids.bff}, rosbridge ${pids.rosbridge}`);
  console.log(`BFF pid ${pids.bff}, rosbridge server pid ${pids.rosbridge}`);

  for (let i = 0; i < CLIENTS; i++) clients.push(new Client(i));
  for (const c of clients) await c.open(); // one login after the other: each its own session
  await sleep(2000); // advertisements and subscriptions settle (rospy connects publishers to subscribers)
  if (interrupted) return shutdown(130, 'interrupted');

  const startRss = { bff: mib(rssKb(pids.bff)), rosbridge: mib(rssKb(pids.rosbridge)) };
  console.log(`RSS with ${CLIENTS} clients connected, before the load: BFF ${f1(startRss.bff)} MiB, rosbridge ${f1(startRss.rosbridge)} MiB`);
  console.log(`per minute: RSS = median of samples every ${SAMPLE_MS / 1000} s in that minute; CPU % of one core (bench = this load generator);`);
  console.log(`host busy % = all ${os.cpus().length} cores, every process on the machine; rx/s = received per second, all clients;`);
  console.log('lost = gaps in the sequence numbers; silent = clients that received nothing in that minute;');
  console.log('latency = receipt - send, same clock; svc = service calls ok/failed/timed out');
  console.log(header());

  const stops = clients.map((c, i) => ticker(RATE, (i * 1000) / RATE / CLIENTS, () => c.publish()));
  stops.push(...clients.map((c, i) => ticker(1, (i * 1000) / CLIENTS, () => c.callService())));
  let touchN = 0;
  const touchTimer = setInterval(() => { clients[touchN++ % CLIENTS].touch(); }, MINUTE_MS / CLIENTS);

  /** @type {any[]} */
  const minutes = [];
  let samples = { bff: [], rosbridge: [] };
  const cpu0 = { bff: cpuTicks(pids.bff), rosbridge: cpuTicks(pids.rosbridge) };
  const restarts = { bff: 0, rosbridge: 0 };
  let bench0 = process.cpuUsage();
  let host0 = hostTicks();
  const t0 = now();
  let nextSample = t0 + SAMPLE_MS;
  for (let m = 1; m <= MINUTES && !interrupted; m++) {
    const end = t0 + m * MINUTE_MS;
    while (now() < end && !interrupted) {
      await sleep(Math.max(0, Math.min(nextSample, end) - now()));
      if (now() >= nextSample - 1) {
        nextSample += SAMPLE_MS;
        const cur = findPids();
        for (const k of /** @type {const} */ (['bff', 'rosbridge'])) {
          if (cur[k] && cur[k] !== pids[k]) { restarts[k]++; note(`${k} pid changed ${pids[k]} -> ${cur[k]} (restarted)`); pids[k] = cur[k]; cpu0[k] = cpuTicks(cur[k]); }
          const kb = rssKb(pids[k]);
          if (Number.isFinite(kb)) samples[k].push(mib(kb));
        }
      }
    }
    if (interrupted) break;
    const w = win;
    win = newWindow();
    const elapsedS = MINUTE_MS / 1000;
    const cpu1 = { bff: cpuTicks(pids.bff), rosbridge: cpuTicks(pids.rosbridge) };
    const bench1 = process.cpuUsage(bench0);
    const host1 = hostTicks();
    const r = {
      minute: m, bffRssMiB: median(samples.bff), rosbridgeRssMiB: median(samples.rosbridge),
      bffRssMaxMiB: Math.max(...samples.bff), rosbridgeRssMaxMiB: Math.max(...samples.rosbridge),
      bffCpuPct: ((cpu1.bff - cpu0.bff) / 100 / elapsedS) * 100, rosbridgeCpuPct: ((cpu1.rosbridge - cpu0.rosbridge) / 100 / elapsedS) * 100,
      benchCpuPct: ((bench1.user + bench1.system) / 1e6 / elapsedS) * 100, hostBusyPct: ((host1[0] - host0[0]) / (host1[1] - host0[1])) * 100,
      sent: w.sent, received: w.received, receivedPerS: w.received / elapsedS, lost: w.lost,
      silentClients: w.perClient.filter((n) => n === 0).length, minPerClient: Math.min(...w.perClient), maxPerClient: Math.max(...w.perClient), reordered: w.reordered,
      p50Ms: w.lat.pct(50), p99Ms: w.lat.pct(99), maxMs: w.lat.max, svcOk: w.svcOk, svcFail: w.svcFail, svcTimeout: w.svcTimeout,
      svcP50Ms: w.svcLat.pct(50), svcP99Ms: w.svcLat.pct(99), status: w.status, wsErrors: w.wsErrors, closes: w.closes,
      reconnects: w.reconnects, skippedTicks: w.skippedTicks, load1: os.loadavg()[0],
    };
    Object.assign(cpu0, cpu1);
    bench0 = process.cpuUsage();
    host0 = host1;
    samples = { bff: [], rosbridge: [] };
    for (const k of ['sent', 'received', 'lost', 'reordered', 'svcOk', 'svcFail', 'svcTimeout', 'status', 'wsErrors', 'closes', 'reconnects', 'skippedTicks']) total[k] += w[k];
    total.lat.merge(w.lat);
    total.svcLat.merge(w.svcLat);
    minutes.push(r);
    console.log(row(r));
  }
  for (const s of stops) s();
  clearInterval(touchTimer);
  await sleep(500); // in-flight messages arrive (not counted: outside the minutes)

  // ---- summary and verdict ----
  const judged = minutes.filter((r) => r.minute >= 2);
  const verdict = {};
  console.log();
  console.log(`Summary (${minutes.length} of ${MINUTES} min${interrupted ? ', interrupted' : ''}): sent ${total.sent}, received ${total.received} ` +
    `(${f1((total.received / Math.max(1, total.sent)) * 100)} %), lost ${total.lost}, reordered ${total.reordered}, ` +
    `latency p50 ${f2(total.lat.pct(50))} / p99 ${f2(total.lat.pct(99))} / max ${f2(total.lat.max)} ms; ` +
    `service calls ok ${total.svcOk}, failed ${total.svcFail}, timed out ${total.svcTimeout}, p50 ${f2(total.svcLat.pct(50))} / p99 ${f2(total.svcLat.pct(99))} ms; ` +
    `status/errors ${total.status + total.wsErrors}, socket closes ${total.closes}, reconnects ${total.reconnects}, skipped publish ticks ${total.skippedTicks}`);
  console.log('(trend: least-squares slope of the same per-minute values, for information: a leak grows steadily, GC moves RSS both ways)');
  console.log(`Verdict: RSS flat within 10 % = after a 1-minute warm-up, max/min of the per-minute RSS (median of that minute's samples, minutes 2 to the last) <= ${FLAT.toFixed(2)}`);
  console.log('process   | start MiB | min 1 MiB | min MiB | max MiB | last MiB | max/min | trend MiB/min | restarts | verdict');
  let fail = false;
  for (const [k, label, key] of /** @type {const} */ ([['bff', 'BFF', 'bffRssMiB'], ['rosbridge', 'rosbridge', 'rosbridgeRssMiB']])) {
    const xs = judged.map((r) => r[key]);
    const lo = Math.min(...xs); const hi = Math.max(...xs);
    const ratio = xs.length ? hi / lo : NaN;
    let v;
    if (xs.length < 2) v = 'n/a: fewer than 2 minutes after the warm-up';
    else if (restarts[k]) v = 'FAIL: restarted';
    else if (MINUTE_MS < 60_000) v = `${ratio <= FLAT ? 'PASS' : 'FAIL'} (indicative: ${MINUTE_MS / 1000} s minutes)`;
    else v = ratio <= FLAT ? 'PASS' : 'FAIL';
    if (v.startsWith('FAIL') && !v.includes('indicative')) fail = true;
    const trend = slope(xs);
    verdict[k] = { startMiB: startRss[k], minute1MiB: minutes[0]?.[key], minMiB: lo, maxMiB: hi, lastMiB: xs.at(-1), ratio, trendMiBPerMin: trend, restarts: restarts[k], verdict: v };
    console.log(`${label.padEnd(9)} | ${f1(startRss[k]).padStart(9)} | ${f1(minutes[0]?.[key]).padStart(9)} | ${f1(lo).padStart(7)} | ${f1(hi).padStart(7)} | ${f1(xs.at(-1)).padStart(8)} | ${(Number.isFinite(ratio) ? ratio.toFixed(3) : '-').padStart(7)} | ${(Number.isFinite(trend) ? (trend >= 0 ? '+' : '') + trend.toFixed(2) : '-').padStart(13)} | ${String(restarts[k]).padStart(8)} | ${v}`);
  }
  if (notes.size) {
    console.log('\nOdd events, by kind: count, first-last time, clients:');
    for (const [kind, e] of [...notes].sort((a, b) => b[1].count - a[1].count).slice(0, 15)) console.log(`  ${String(e.count).padStart(6)} x ${e.first}-${e.last} ${e.clients.size ? `${e.clients.size} clients` : ''}: ${kind}`);
  }
  const logLines = stack.output().split('\n').filter((l) => /error|traceback|exception|closing \/ros|exited/i.test(l));
  if (logLines.length) { console.log(`\nStack log: ${logLines.length} lines with error/exception/closing /ros/exited, first ones:`); for (const l of logLines.slice(0, 10)) console.log(`  ${l.slice(0, 200)}`); }

  const doc = { bench: 'soak', date, host: { cores: os.cpus().length, load: os.loadavg() }, options: { minutes: MINUTES, minuteMs: MINUTE_MS, quick: QUICK, clients: CLIENTS, rateHz: RATE },
    definition: `after a 1-minute warm-up, max/min of the per-minute RSS (median of samples every ${SAMPLE_MS / 1000} s) <= ${FLAT}`,
    interrupted, startRss, minutes,
    total: { sent: total.sent, received: total.received, lost: total.lost, reordered: total.reordered, p50Ms: total.lat.pct(50), p99Ms: total.lat.pct(99), maxMs: total.lat.max,
      svcOk: total.svcOk, svcFail: total.svcFail, svcTimeout: total.svcTimeout, svcP50Ms: total.svcLat.pct(50), svcP99Ms: total.svcLat.pct(99),
      status: total.status, wsErrors: total.wsErrors, closes: total.closes, reconnects: total.reconnects, skippedTicks: total.skippedTicks },
    verdict, notes: [...notes].map(([kind, e]) => ({ kind, count: e.count, first: e.first, last: e.last, clients: e.clients.size })) };
  const files = [JSON_OUT, fs.existsSync(path.join(REPO_ROOT, 'bench/results')) ? path.join(REPO_ROOT, `bench/results/soak-${MINUTE_MS < 60_000 ? 'quick-' : ''}${date.slice(0, 10)}.json`) : null].filter(Boolean);
  for (const f of files) { fs.writeFileSync(f, JSON.stringify(doc, null, 2) + '\n'); console.log(`figures written to ${f}`); }

  await shutdown(interrupted ? 130 : fail ? 1 : 0, interrupted ? 'interrupted: summary of the minutes completed' : '');
}

main().catch((e) => {
  if (interrupted) return shutdown(130, 'interrupted');
  console.error(`soak bench: ${e.stack || e}`);
  return shutdown(1);
});
