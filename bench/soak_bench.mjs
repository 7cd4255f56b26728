#!/usr/bin/env node
// Soak (issues 15 and 28, `npm run bench -- --soak`): a whole simulated cell in use for minutes, watching the memory
// of every process of the stack, their logs and whether every client is still served at the end. Starts its own
// stack (scripts/stack.js with config/demo-cell.yaml and the simulated cell, UR_SIM=1, ports 29080-29083, UR_HOST
// 127.0.0.41: away from the e2e stacks' 18080.. and 127.0.0.9), stops it at the end or on Ctrl-C.
//
// The relay load (issue 15): --clients admin clients, each logged in on its own (own session cookie) with /ros
// open. Client i advertises /soak/c<i> (std_msgs/String "<seq> <send time>"), publishes it at --rate Hz and
// subscribes to /soak/c<i+1 mod n> (queue_length 10), so every message goes BFF -> rosbridge -> ROS (TCPROS) ->
// rosbridge -> BFF -> a client. Once a second each client calls a service, /cell/get_mode and /rosapi/topics in
// turn (the second one goes through the BFF's rosapi filter). Once a minute each client GETs /api/auth/me, as the
// app does, and keeps a renewed cookie. A closed socket is reopened after 1 s (logging in again if refused).
//
// The cell in use (issue 28; bench/soak_cell.mjs), each its own login and /ros socket, as the app's pages:
// - a camera viewer (operator, the Cameras page): the first stream (/cell/camera/workbench/image/compressed) in
//   CBOR, throttle_rate 33 ms, queue_length 1; frames (JPEG bytes) counted, the longest gap between two.
// - a jogging session (admin, the Manual page): the arm's driver state, /cell/manual/groups, the jog topic
//   advertised; takes the control lease over HTTP (POST /api/control/take, heartbeat every 500 ms, release), then
//   jogs joint 1 (the base) hold-to-run as the page does: the JogCommand (speed 0.5, as e2e/lib/manual.js jogMsg)
//   at once and every 50 ms for 1 s, then direction 0; + then -, 0.3 s apart, 0.7 s pause, twice per window, the
//   first direction alternating, so the arm ends where it began (the process goes home first anyway). An arm away
//   from home (a run stopped or failed mid-cycle) is first moved straight up when low, then home (Move to pose,
//   Move to home): swinging the base with the fingers around a part in the fixture ends in a protective stop. A
//   jog is done when the driver's state shows the joint moved > 0.005 rad (soak_cell.mjs MOVED_RAD), refused
//   otherwise (the BFF's or the driver's reason noted); travel median and minimum per minute. Heartbeats the driver
//   dropped because they reached it later than the jog timeout (docs/ros-interfaces.md) are counted apart: the
//   jog's motion may pause, and the host's load shows in how many there are.
// - a running process (operator, the Process page): /cell/process/state and /log and the status fields' topics;
//   takes the lease, Start {cycles}, releases the lease when the run ended; cycles counted from the state's
//   cycle counter.
// One arm, one lease: a real cell does not jog an arm its process is moving (the driver ignores a jog during a
// move), and the lease lets one session at a time command motion. So the two take turns, as a shift would:
// the process runs until the fixture is full (the demo cell's pose tables have 3 entries: 3 cycles fill its 3
// pockets, a 4th would pick at an empty place); the operator releases control; the admin takes it, jogs (2 pairs,
// ~6 s) and releases control; the sim's feeder (/sim/restock, called on rosbridge directly: it is the world's, not
// a user's) puts the 3 parts back where the process picks them, as a feeder or an operator refilling a real cell
// would; the operator takes control and starts again. The manual session's turn comes first. A round takes about
// 50 s (3 cycles of ~13 s, ~7 s of jogging): ~3.5 cycles and ~2.5 jog windows a minute. A run that ends in error counts as a process error; after 3 in a row no more Starts.
// At the end (after the last minute): the operator stops the process if it runs (Stop needs no lease), the admin
// takes control, clears the arm (as above) and jogs once more: "can still take the lease, and the jog moves the arm".
//
// Every minute: RSS of every process of the stack (e2e/lib/stack.js pidsOfStack: the processes whose environment
// names this stack's DATA_DIR), grouped by name (ROS nodes by node name: rosbridge_websocket, manual, process, ...;
// roscore, rosmaster, roslaunch, sim, sim renderer, bff, stack, watchdog, ...), as the median of samples every 5 s in
// that minute (/proc/<pid>/status VmRSS, summed over a group's processes), and CPU; for the relay: messages
// sent/received, loss (sequence gaps), latency p50/p99 (receipt - send, one clock), service calls, errors and status
// messages, reconnects, clients that received nothing; for the cell: camera frames and fps, jogs done/refused,
// cycles completed, process errors, parts put back, lease takes/refusals/losses; error lines in the logs.
// Verdict (a table; exit 1 on any FAIL):
// - RSS flat within 10 %, for every process: after a 1-minute warm-up, max/min of the per-minute RSS values
//   (minutes 2..N) <= 1.10, and no restart (a group's pid replaced) and not gone. The flight recorder's warm-up is
//   its ring's span (the cell file's recorder before_s + after_s, in whole minutes): it fills that ring by design
//   (the recorder bench: 53.7 MiB at 30 s, 62.0 from 150 s to 480 s), so it is judged from the minute after;
// - no error in any log: the stack's output (DATA_DIR/stack.log) and its ROS log files (DATA_DIR/ros/log, but
//   rosout.log, which repeats the nodes' own) written after start-up: lines with Traceback, ERROR, FATAL,
//   "[bff] ... error", uncaught/unhandled, exited, "process has died"; each listed (start-up ones listed apart,
//   not judged);
// - every client still live at the end: each relay client received messages in the last minute; the camera viewer
//   got frames in the last minute; the jogging session took the lease at the end and its jog moved the arm; the
//   process completed a cycle in the last 3 minutes (the whole soak when shorter);
// - the cell's work without refusals or errors: no process run ended in error, every part put back, no jog
//   refused, the lease never refused nor lost (a lapsed heartbeat).
// Options: --minutes N (10), --clients N (25), --rate HZ (100), --json FILE (also written to
// bench/results/soak-<date>.json when bench/results exists).
// BENCH_QUICK=1 (npm run bench -- --quick [soak]): 3 "minutes" of 8 s each (SOAK_MINUTE_MS, --minutes still win),
// the same figures for a quick look; the RSS verdict over windows that short is indicative only (no exit 1 for it;
// a restart still fails), and so is the process's when the soak is under 40 s (a round takes longer); the JSON goes
// to bench/results/soak-quick-<date>.json, never over the full run's.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { WebSocket } from 'ws';
import yaml from 'js-yaml';
import { stackEnv, addUser, startStack, stopStack, REPO_ROOT } from '../e2e/lib/stack.js';
import { HttpSession, RosLink, Lease, CameraViewer, ManualSession, ProcessSession, CellSchedule, ProcWatch, LogWatch, simFeeder } from './soak_cell.mjs';

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
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s.length ? (s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2) : NaN; };
/** Least-squares slope of ys against 0..n-1 (per step). @param {number[]} ys */
const slope = (ys) => { const n = ys.length; if (n < 2) return NaN; const mx = (n - 1) / 2; const my = ys.reduce((a, b) => a + b, 0) / n; let sxy = 0; let sxx = 0; ys.forEach((y, x) => { sxy += (x - mx) * (y - my); sxx += (x - mx) ** 2; }); return sxy / sxx; };
/** [busy, total] jiffies of the whole host (all cores) */
const hostTicks = () => { const f = fs.readFileSync('/proc/stat', 'utf8').split('\n')[0].trim().split(/\s+/).slice(1).map(Number); const tot = f.reduce((a, b) => a + b, 0); return [tot - f[3] - (f[4] || 0), tot]; };

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
/** The cell's figures of one minute (bench/soak_cell.mjs writes them). */
const newCellWindow = () => ({ camFrames: 0, camBytes: 0, camBad: 0, camMaxGapMs: 0, jogOk: 0, jogRefused: 0, jogLate: 0, jogTravel: [], cycles: 0, cycleTimes: [], runs: 0,
  processErrors: 0, processLogErrors: 0, restocked: 0, restockErrors: 0, homed: 0, leaseTakes: 0, leaseRefused: 0, leaseLost: 0 });
let cellWin = newCellWindow();
const cellTotal = newCellWindow();
const getCellWin = () => cellWin;
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
const CELL_FILE = path.join(REPO_ROOT, 'config/demo-cell.yaml');
const cell = /** @type {any} */ (yaml.load(fs.readFileSync(CELL_FILE, 'utf8')));
const RING_S = Number(cell.recorder?.before_s ?? 0) + Number(cell.recorder?.after_s ?? 0);
/** Whole minutes before a process's RSS is judged. @param {string} name a process group of the stack */
const warmupOf = (name) => (name.includes('recorder') ? Math.max(1, Math.ceil((RING_S * 1000) / MINUTE_MS)) : 1);
const UR_HOST = '127.0.0.41';
// The simulated cell as `npm start` runs it (scripts/stack.js starts sim/ at UR_HOST), as e2e/lib/global-setup.js.
const env = stackEnv({ port: PORT, masterPort: PORT + 1, rosbridgePort: PORT + 2, urHost: UR_HOST, extraEnv: { CELL_CONFIG: CELL_FILE, UR_SIM: '1' } });
delete env.UR_HOSTS; // (an e2e shell's per-arm addresses must not leak in: one arm, at UR_HOST)
delete env.SIM_ARGS;
addUser(env, USER, 'admin', PASSWORD);
const CELL_USERS = { jog: ['soak-jog', 'admin'], process: ['soak-process', 'operator'], camera: ['soak-camera', 'operator'] };
for (const [name, role] of Object.values(CELL_USERS)) addUser(env, name, role, `${name}-password`);
const base = `http://127.0.0.1:${PORT}`;
let stack = null;
let stopping = false;
/** @type {Client[]} */
const clients = [];
/** @type {RosLink[]} the cell's sessions' sockets */
const cellLinks = [];

async function shutdown(code, why) {
  if (stopping) return;
  stopping = true;
  if (why) console.log(why);
  for (const c of clients) c.close();
  for (const l of cellLinks) l.close();
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

const f0 = (x) => (Number.isFinite(x) ? x.toFixed(0) : '-');
/** The cell's figures of one minute, one line. */
const cellLine = (c) => `     cell: camera ${c.camFrames} frames (${f1(c.camFps)} fps, max gap ${f2(c.camMaxGapMs / 1000)} s, ${f1(c.camMiB)} MiB${c.camBad ? `, ${c.camBad} bad` : ''})` +
  ` | jogs ${c.jogOk} done, ${c.jogRefused} refused${c.jogLate ? `, ${c.jogLate} late heartbeats dropped` : ''}${c.jogOk ? ` (travel median ${f2(c.jogTravelMedian)}, min ${f2(c.jogTravelMin)} rad)` : ''}${c.homed ? `, ${c.homed}x homed first` : ''}` +
  ` | process ${c.cycles} cycles${c.cycles ? ` (median ${f1(c.cycleMedianS)} s)` : ''}, ${c.runs} starts, ${c.processErrors} errors${c.processLogErrors ? ` (${c.processLogErrors} error log entries)` : ''}` +
  ` | parts put back ${c.restocked}${c.restockErrors ? `, ${c.restockErrors} failed` : ''} | lease ${c.leaseTakes} taken${c.leaseRefused ? `, ${c.leaseRefused} refused` : ''}${c.leaseLost ? `, ${c.leaseLost} lost` : ''}` +
  ` | log errors ${c.logErrors}`;
/** Every process's RSS (MiB, that minute's median) and CPU % of one core, one line. */
const procLine = (pm, order) => `     RSS MiB (CPU %): ${order.filter((n) => pm[n]).map((n) => `${n} ${f1(pm[n].rssMiB)} (${f0(pm[n].cpuPct)})`).join(', ')}` +
  ` | all ${f1(Object.values(pm).reduce((a, p) => a + (p.rssMiB || 0), 0))} MiB`;

async function main() {
  const date = new Date().toISOString();
  console.log(`Soak: the demo cell in use (camera viewer, jogging, process) + ${CLIENTS} clients x ${RATE} Hz through the BFF's /ros for ${MINUTES} min${MINUTE_MS !== 60_000 ? ` of ${MINUTE_MS / 1000} s each${QUICK ? ', quick' : ''}` : ''} (${date.slice(0, 16)}Z, ${os.cpus().length} cores, load ${os.loadavg().map((l) => l.toFixed(1)).join(' ')})`);
  console.log(`starting the stack (${path.relative(REPO_ROOT, CELL_FILE)}, simulated cell at ${UR_HOST}, BFF on ${PORT}, rosbridge on ${PORT + 2}, DATA_DIR ${env.DATA_DIR}) ...`);
  const tStack = now();
  stack = await startStack(env, 120_000);
  if (interrupted) return shutdown(130, 'interrupted');
  console.log(`stack ready in ${f1((now() - tStack) / 1000)} s`);
  const procs = new ProcWatch(env.DATA_DIR, note);
  const logs = new LogWatch(stack, env.DATA_DIR);

  for (let i = 0; i < CLIENTS; i++) clients.push(new Client(i));
  for (const c of clients) await c.open(); // one login after the other: each its own session

  // The cell's sessions, each its own login and /ros socket.
  const session = async (key) => {
    const [user] = CELL_USERS[key];
    const http = new HttpSession(base, user, `${user}-password`);
    await http.login();
    const link = new RosLink(http, PORT, key, note);
    cellLinks.push(link);
    await link.open();
    return { http, link };
  };
  const cam = await session('camera');
  const jogS = await session('jog');
  const procS = await session('process');
  const camTopic = cell.video.streams[0].topic;
  const viewer = new CameraViewer(cam.link, camTopic, getCellWin);
  viewer.start();
  const manual = new ManualSession(jogS.link, cell, note, getCellWin);
  await manual.open();
  const processS = new ProcessSession(procS.link, cell, note, getCellWin);
  processS.open();
  const jogLease = new Lease(jogS.http, 'jog session', note, getCellWin);
  const schedule = new CellSchedule({ manual, process: processS, jogLease, processLease: new Lease(procS.http, 'process session', note, getCellWin), cell, note, win: getCellWin, feeder: simFeeder(PORT + 2) });
  console.log(`waiting for the robot driver and the process server ...`);
  await schedule.ready(90_000, () => interrupted);
  await sleep(2000); // advertisements and subscriptions settle (rospy connects publishers to subscribers)
  if (interrupted) return shutdown(130, 'interrupted');

  const groups = procs.start();
  const startRss = {};
  for (const [name, pids] of groups) startRss[name] = pids.map((p) => { try { return Number(/VmRSS:\s+(\d+)/.exec(fs.readFileSync(`/proc/${p}/status`, 'utf8'))[1]); } catch { return 0; } }).reduce((a, b) => a + b, 0) / 1024;
  const order = [...groups.keys()].sort((a, b) => startRss[b] - startRss[a]);
  console.log(`${groups.size} processes in the stack, RSS with every client connected, before the load (MiB): ${order.map((n) => `${n} ${f1(startRss[n])}${groups.get(n).length > 1 ? ` (${groups.get(n).length} pids)` : ''}`).join(', ')}`);
  logs.mark();
  const startupErrors = logs.startup();
  console.log(`per minute: RSS = median of samples every ${SAMPLE_MS / 1000} s in that minute; CPU % of one core (bench = this load generator);`);
  console.log(`host busy % = all ${os.cpus().length} cores, every process on the machine; rx/s = received per second, all clients;`);
  console.log('lost = gaps in the sequence numbers; silent = clients that received nothing in that minute;');
  console.log('latency = receipt - send, same clock; svc = service calls ok/failed/timed out;');
  console.log(`cell: the camera viewer's frames (${camTopic}), jogs, process cycles, parts put back, lease, error lines in the logs; then every process's RSS`);
  console.log(header());

  const stops = clients.map((c, i) => ticker(RATE, (i * 1000) / RATE / CLIENTS, () => c.publish()));
  stops.push(...clients.map((c, i) => ticker(1, (i * 1000) / CLIENTS, () => c.callService())));
  let touchN = 0;
  const touchTimer = setInterval(() => { clients[touchN++ % CLIENTS].touch(); }, MINUTE_MS / CLIENTS);
  const cellTouch = setInterval(() => { for (const s of [cam, jogS, procS]) s.http.touch().catch((e) => note(`/api/auth/me ${e.message}`)); }, Math.min(MINUTE_MS, 60_000));
  const runP = schedule.run().catch((e) => note(`cell schedule stopped: ${e.stack || e}`));

  /** @type {any[]} */
  const minutes = [];
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
        procs.sample(m);
      }
    }
    if (interrupted) break;
    const w = win;
    win = newWindow();
    const cw = cellWin;
    cellWin = newCellWindow();
    const elapsedS = MINUTE_MS / 1000;
    const pm = procs.endMinute(elapsedS);
    const bench1 = process.cpuUsage(bench0);
    const host1 = hostTicks();
    const newErrors = logs.scanNew();
    const c = {
      camFrames: cw.camFrames, camFps: cw.camFrames / elapsedS, camMaxGapMs: cw.camMaxGapMs, camMiB: cw.camBytes / 1048576, camBad: cw.camBad,
      jogOk: cw.jogOk, jogRefused: cw.jogRefused, jogLate: cw.jogLate, jogTravelMedian: median(cw.jogTravel), jogTravelMin: Math.min(...cw.jogTravel), homed: cw.homed, cycles: cw.cycles, cycleMedianS: median(cw.cycleTimes), runs: cw.runs,
      processErrors: cw.processErrors, processLogErrors: cw.processLogErrors, restocked: cw.restocked, restockErrors: cw.restockErrors,
      leaseTakes: cw.leaseTakes, leaseRefused: cw.leaseRefused, leaseLost: cw.leaseLost, logErrors: newErrors.length,
    };
    const r = {
      minute: m, bffRssMiB: pm.bff?.rssMiB, rosbridgeRssMiB: pm.rosbridge_websocket?.rssMiB,
      bffCpuPct: pm.bff?.cpuPct, rosbridgeCpuPct: pm.rosbridge_websocket?.cpuPct,
      benchCpuPct: ((bench1.user + bench1.system) / 1e6 / elapsedS) * 100, hostBusyPct: ((host1[0] - host0[0]) / (host1[1] - host0[1])) * 100,
      sent: w.sent, received: w.received, receivedPerS: w.received / elapsedS, lost: w.lost,
      silentClients: w.perClient.filter((n) => n === 0).length, minPerClient: Math.min(...w.perClient), maxPerClient: Math.max(...w.perClient), reordered: w.reordered,
      p50Ms: w.lat.pct(50), p99Ms: w.lat.pct(99), maxMs: w.lat.max, svcOk: w.svcOk, svcFail: w.svcFail, svcTimeout: w.svcTimeout,
      svcP50Ms: w.svcLat.pct(50), svcP99Ms: w.svcLat.pct(99), status: w.status, wsErrors: w.wsErrors, closes: w.closes,
      reconnects: w.reconnects, skippedTicks: w.skippedTicks, load1: os.loadavg()[0], cell: c, processes: pm,
    };
    bench0 = process.cpuUsage();
    host0 = host1;
    for (const k of ['sent', 'received', 'lost', 'reordered', 'svcOk', 'svcFail', 'svcTimeout', 'status', 'wsErrors', 'closes', 'reconnects', 'skippedTicks']) total[k] += w[k];
    total.lat.merge(w.lat);
    total.svcLat.merge(w.svcLat);
    for (const k of Object.keys(cellTotal)) if (Array.isArray(cw[k])) cellTotal[k].push(...cw[k]); else cellTotal[k] += cw[k];
    minutes.push(r);
    for (const n of Object.keys(pm)) if (!order.includes(n)) order.push(n);
    console.log(row(r));
    console.log(cellLine(c));
    console.log(procLine(pm, order));
  }
  const tEnd = now();
  const camLastAt = viewer.lastAt;
  for (const s of stops) s();
  clearInterval(touchTimer);
  await sleep(500); // in-flight messages arrive (not counted: outside the minutes)
  const lastMinute = minutes.at(-1);

  // ---- the end: the process stopped, the jogging session takes control and jogs once more ----
  let fin = { took: false, jog: null };
  if (!interrupted) {
    console.log('\nthe end: stopping the process if it runs; the jogging session takes control and jogs once more ...');
    fin = await schedule.finish(runP);
  } else schedule.stopping = true;
  clearInterval(cellTouch);
  logs.scanNew();
  const soakErrors = logs.found;

  // ---- summary and verdict ----
  /** @param {string} name */
  const judgedOf = (name) => minutes.filter((r) => r.minute > warmupOf(name));
  const indicative = MINUTE_MS < 60_000;
  const soakS = (tEnd - t0) / 1000;
  console.log();
  console.log(`Summary (${minutes.length} of ${MINUTES} min${interrupted ? ', interrupted' : ''}): relay: sent ${total.sent}, received ${total.received} ` +
    `(${f1((total.received / Math.max(1, total.sent)) * 100)} %), lost ${total.lost}, reordered ${total.reordered}, ` +
    `latency p50 ${f2(total.lat.pct(50))} / p99 ${f2(total.lat.pct(99))} / max ${f2(total.lat.max)} ms; ` +
    `service calls ok ${total.svcOk}, failed ${total.svcFail}, timed out ${total.svcTimeout}, p50 ${f2(total.svcLat.pct(50))} / p99 ${f2(total.svcLat.pct(99))} ms; ` +
    `status/errors ${total.status + total.wsErrors}, socket closes ${total.closes}, reconnects ${total.reconnects}, skipped publish ticks ${total.skippedTicks}`);
  console.log(`cell: camera ${cellTotal.camFrames} frames (${f1(cellTotal.camFrames / soakS)} fps, ${cellTotal.camBad} bad); jogs ${cellTotal.jogOk} done, ${cellTotal.jogRefused} refused, ${cellTotal.jogLate} late heartbeats dropped by the driver` +
    ` (travel median ${f2(median(cellTotal.jogTravel))}, min ${f2(Math.min(...cellTotal.jogTravel))} rad); process ${cellTotal.cycles} cycles (median ${f1(median(cellTotal.cycleTimes))} s) in ${cellTotal.runs} starts, ${cellTotal.processErrors} errors;` +
    ` parts put back ${cellTotal.restocked}, ${cellTotal.restockErrors} failed; lease taken ${cellTotal.leaseTakes}, refused ${cellTotal.leaseRefused}, lost ${cellTotal.leaseLost};` +
    ` camera/jog/process sockets reconnected ${cellLinks.map((l) => l.reconnects).reduce((a, b) => a + b, 0)} times`);

  /** @type {{check: string, value: string, verdict: string}[]} */
  const verdictRows = [];
  let fail = false;
  const judge = (check, value, verdict) => {
    verdictRows.push({ check, value, verdict });
    if (verdict.startsWith('FAIL') && !verdict.includes('indicative')) fail = true;
  };

  // RSS of every process
  console.log('\nRSS of every process, MiB (median of each minute), and CPU % of one core (mean over the minutes):');
  const rssHead = ['process'.padEnd(20), 'start', ...minutes.map((r) => `m${r.minute}`), 'CPU %'];
  console.log(rssHead.map((h, k) => (k ? h.padStart(7) : h)).join(' '));
  const rssVerdict = {};
  for (const name of order) {
    const per = minutes.map((r) => r.processes[name]?.rssMiB);
    const cpus = minutes.map((r) => r.processes[name]?.cpuPct).filter(Number.isFinite);
    console.log([name.padEnd(20), f1(startRss[name]).padStart(7), ...per.map((x) => f1(x).padStart(7)), f1(cpus.reduce((a, b) => a + b, 0) / Math.max(1, cpus.length)).padStart(7)].join(' '));
    const judged = judgedOf(name);
    const xs = judged.map((r) => r.processes[name]?.rssMiB).filter(Number.isFinite);
    const lo = Math.min(...xs); const hi = Math.max(...xs);
    const ratio = xs.length ? hi / lo : NaN;
    const trend = slope(xs);
    const anon = judged.map((r) => r.processes[name]?.anonMiB).filter(Number.isFinite);
    const anonLo = Math.min(...anon); const anonHi = Math.max(...anon);
    const restarts = procs.restarts.get(name) || 0;
    let v;
    if (procs.gone.has(name)) v = `FAIL: gone in minute ${procs.gone.get(name)}`;
    else if (restarts) v = `FAIL: restarted (${restarts}x)`;
    else if (procs.appeared.has(name)) v = `n/a: appeared in minute ${procs.appeared.get(name)}`;
    else if (xs.length < 2) v = 'n/a: fewer than 2 minutes after the warm-up';
    else if (indicative) v = `${ratio <= FLAT ? 'PASS' : 'FAIL'} (indicative: ${MINUTE_MS / 1000} s minutes)`;
    else v = ratio <= FLAT ? 'PASS' : 'FAIL';
    rssVerdict[name] = { startMiB: startRss[name], minute1MiB: minutes[0]?.processes[name]?.rssMiB, minMiB: lo, maxMiB: hi, lastMiB: xs.at(-1), ratio, trendMiBPerMin: trend,
      anonMinMiB: anonLo, anonMaxMiB: anonHi, anonTrendMiBPerMin: slope(anon), restarts, verdict: v };
    judge(`RSS flat within 10 %: ${name}`, xs.length ? `${f1(lo)}-${f1(hi)} MiB, max/min ${Number.isFinite(ratio) ? ratio.toFixed(3) : '-'}, trend ${Number.isFinite(trend) ? (trend >= 0 ? '+' : '') + trend.toFixed(2) : '-'} MiB/min` +
      (anon.length ? `; private ${f1(anonLo)}-${f1(anonHi)}` : '') : '-', v);
  }

  // Logs
  judge('no error in any log (after start-up)', `${soakErrors.length} error lines`, soakErrors.length ? 'FAIL' : 'PASS');

  // Every client still live at the end
  if (lastMinute) {
    judge('relay clients live at the end', `${CLIENTS - lastMinute.silentClients}/${CLIENTS} received in the last minute (min ${lastMinute.minPerClient} a client)`, lastMinute.silentClients ? 'FAIL' : 'PASS');
    const lc = lastMinute.cell;
    judge('camera viewer live at the end', `${lc.camFrames} frames in the last minute (${f1(lc.camFps)} fps), the last ${f1((tEnd - camLastAt) / 1000)} s before the end`, lc.camFrames ? 'PASS' : 'FAIL');
  } else judge('clients live at the end', 'no minute completed', 'n/a');
  if (!interrupted) {
    const j = fin.jog;
    judge('jogging session live at the end', fin.took ? (j ? `took the lease; its last jog ${j.moved ? `moved the arm ${f2(j.travel)} rad` : `did not move the arm: ${j.why}`}` : 'took the lease') : 'could not take the lease', fin.took && j?.moved ? 'PASS' : 'FAIL');
  }
  const liveMs = Math.min(180_000, tEnd - t0);
  const sinceCycle = processS.lastCycleAt ? (tEnd - processS.lastCycleAt) / 1000 : NaN;
  const processLive = processS.lastCycleAt > 0 && tEnd - processS.lastCycleAt <= liveMs;
  const shortSoak = soakS < 40;
  judge(`process live at the end (a cycle in the last ${f0(liveMs / 1000)} s)`, processS.lastCycleAt ? `${processS.cyclesTotal} cycles, the last ${f1(sinceCycle)} s before the end` : 'no cycle completed',
    processLive ? 'PASS' : `FAIL${shortSoak ? ` (indicative: a ${f0(soakS)} s soak)` : ''}`);
  const cellErrors = cellTotal.processErrors + cellTotal.restockErrors + cellTotal.jogRefused + cellTotal.leaseRefused + cellTotal.leaseLost;
  judge('cell work without refusals or errors', `process errors ${cellTotal.processErrors}, parts not put back ${cellTotal.restockErrors}, jogs refused ${cellTotal.jogRefused}, lease refused ${cellTotal.leaseRefused}, lost ${cellTotal.leaseLost}`,
    cellErrors ? 'FAIL' : 'PASS');

  console.log(`\nVerdict (RSS: after a 1-minute warm-up (the recorder: ${warmupOf('recorder')} min, its ring's span), max/min of the per-minute RSS, from the minute after to the last, <= ${FLAT.toFixed(2)}, no restart; trend = least-squares slope, for information):`);
  const wc = Math.max(...verdictRows.map((v) => v.check.length));
  const wv = Math.max(...verdictRows.map((v) => v.value.length));
  for (const v of verdictRows) console.log(`  ${v.check.padEnd(wc)} | ${v.value.padEnd(wv)} | ${v.verdict}`);

  if (soakErrors.length) {
    console.log(`\nError lines in the logs during the soak (${soakErrors.length}; by text, numbers folded; source, count, first line verbatim):`);
    printErrors(soakErrors);
  }
  if (startupErrors.length) {
    console.log(`\nError lines during start-up (not judged; ${startupErrors.length}):`);
    printErrors(startupErrors);
  }
  if (notes.size) {
    console.log('\nOdd events, by kind: count, first-last time, clients:');
    for (const [kind, e] of [...notes].sort((a, b) => b[1].count - a[1].count).slice(0, 25)) console.log(`  ${String(e.count).padStart(6)} x ${e.first}-${e.last} ${e.clients.size ? `${e.clients.size} clients` : ''}: ${kind}`);
  }

  const doc = { bench: 'soak', date, host: { cores: os.cpus().length, load: os.loadavg() },
    options: { minutes: MINUTES, minuteMs: MINUTE_MS, quick: QUICK, clients: CLIENTS, rateHz: RATE, cell: path.relative(REPO_ROOT, CELL_FILE), urHost: UR_HOST, cameraTopic: camTopic },
    definition: `RSS: after a 1-minute warm-up (the recorder: ${warmupOf('recorder')} min, its ring's span), max/min of the per-minute RSS (median of samples every ${SAMPLE_MS / 1000} s) <= ${FLAT}, per process of the stack`,
    interrupted, startRss, minutes,
    total: { sent: total.sent, received: total.received, lost: total.lost, reordered: total.reordered, p50Ms: total.lat.pct(50), p99Ms: total.lat.pct(99), maxMs: total.lat.max,
      svcOk: total.svcOk, svcFail: total.svcFail, svcTimeout: total.svcTimeout, svcP50Ms: total.svcLat.pct(50), svcP99Ms: total.svcLat.pct(99),
      status: total.status, wsErrors: total.wsErrors, closes: total.closes, reconnects: total.reconnects, skippedTicks: total.skippedTicks },
    cell: { ...cellTotal, jogTravel: undefined, cycleTimes: undefined, jogTravelMedian: median(cellTotal.jogTravel), cycleMedianS: median(cellTotal.cycleTimes), end: fin },
    verdict: { rss: rssVerdict, checks: verdictRows }, logErrors: soakErrors, startupLogErrors: startupErrors,
    notes: [...notes].map(([kind, e]) => ({ kind, count: e.count, first: e.first, last: e.last, clients: e.clients.size })) };
  const files = [JSON_OUT, fs.existsSync(path.join(REPO_ROOT, 'bench/results')) ? path.join(REPO_ROOT, `bench/results/soak-${MINUTE_MS < 60_000 ? 'quick-' : ''}${date.slice(0, 10)}.json`) : null].filter(Boolean);
  for (const f of files) { fs.writeFileSync(f, JSON.stringify(doc, null, 2) + '\n'); console.log(`figures written to ${f}`); }

  await shutdown(interrupted ? 130 : fail ? 1 : 0, interrupted ? 'interrupted: summary of the minutes completed' : '');
}

/** Error lines folded by text (numbers, hex ids and paths' run ids as #), most frequent first. @param {{source: string, line: string, detail: string}[]} found */
function printErrors(found) {
  const byKind = new Map();
  for (const f of found) {
    const kind = `${f.source}: ${f.line.replace(/\d{4}-\d\d-\d\d[ T][\d:,.]+/g, '<time>').replace(/0x[0-9a-f]+|\d+(\.\d+)?/gi, '#')}`;
    const e = byKind.get(kind) || { n: 0, first: f };
    e.n++;
    byKind.set(kind, e);
  }
  for (const [, e] of [...byKind].sort((a, b) => b[1].n - a[1].n).slice(0, 30)) {
    console.log(`  ${String(e.n).padStart(4)} x [${e.first.source}] ${e.first.line.slice(0, 300)}`);
    if (e.first.detail) console.log(`         -> ${e.first.detail.slice(0, 300)}`);
  }
  if (byKind.size > 30) console.log(`  ... and ${byKind.size - 30} more kinds`);
}

main().catch((e) => {
  if (interrupted) return shutdown(130, 'interrupted');
  console.error(`soak bench: ${e.stack || e}`);
  return shutdown(1);
});
