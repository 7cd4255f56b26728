// The soak's cell side (bench/soak_bench.mjs): sessions that use the simulated demo cell the way the app's pages
// do, the RSS of every process of the stack, and the stack's logs. Plain Node (ws, cbor-x), no browser.
//
// - CameraViewer: the Cameras page: one stream, subscribed over /ros in CBOR, throttle 33 ms, queue_length 1
//   (app/src/lib/ui/CameraView.svelte, features/video/logic.js THROTTLE_MS); counts frames (JPEG bytes).
// - ManualSession: the Manual page of an admin: the group's driver state, /cell/manual/groups at open, the jog
//   topic advertised (queue_size 1); a hold-to-run jog = the same JogCommand at once and every 50 ms while "held",
//   then one with direction 0 (features/manual/logic.js JogHold, jogCommand); service moves and tool actions
//   (the page's Move to pose and gripper buttons) to put the parts back.
// - ProcessSession: the Process page of an operator: /cell/process/state and /log, the status fields' topics
//   (throttle 200 ms, queue_length 1, StatusPanel.svelte); Start {cycles} and Stop.
// - Lease: the control lease over HTTP as app/src/lib/core/lease.svelte.js: take, heartbeat every 500 ms while
//   held, release.
// - CellSchedule: one arm, one lease: the process and the manual session take turns (see soak_bench.mjs's header).
// - ProcWatch: every process of the stack (pidsOfStack), grouped by name, RSS samples and CPU.
// - LogWatch: error lines in the stack's output and in its ROS log files written after a mark.
import fs from 'node:fs';
import path from 'node:path';
import { WebSocket } from 'ws';
import { decode as cborDecode } from 'cbor-x';
import { pidsOfStack } from '../e2e/lib/stack.js';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const now = () => performance.now();
/** The p-th percentile (nearest rank) of xs, NaN when empty. @param {number[]} xs @param {number} p */
export const pct = (xs, p) => { const s = [...xs].sort((a, b) => a - b); return s.length ? s[Math.min(s.length - 1, Math.floor((p / 100) * s.length))] : NaN; };

/** Log in to the BFF at base; the session cookie ("name=value"). @param {string} base @param {string} username @param {string} password */
export async function loginCookie(base, username, password) {
  const r = await fetch(`${base}/api/auth/login`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ username, password }) });
  if (!r.ok) throw new Error(`login: HTTP ${r.status} ${await r.text()}`);
  return String(r.headers.get('set-cookie')).split(';')[0];
}

export const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s.length ? (s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2) : NaN; };

/** A login of its own (its own session cookie), renewed from every answer's Set-Cookie. */
export class HttpSession {
  /** @param {string} base @param {string} user @param {string} password */
  constructor(base, user, password) {
    this.base = base;
    this.user = user;
    this.password = password;
    this.cookie = '';
  }

  async login() {
    const r = await fetch(`${this.base}/api/auth/login`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ username: this.user, password: this.password }) });
    if (!r.ok) throw new Error(`login ${this.user}: HTTP ${r.status} ${await r.text()}`);
    this.cookie = String(r.headers.get('set-cookie')).split(';')[0];
  }

  /** @param {string} method @param {string} p @param {any} [body] @returns {Promise<{status: number, data: any}>} */
  async request(method, p, body) {
    const headers = { cookie: this.cookie, accept: 'application/json', ...(body !== undefined ? { 'content-type': 'application/json' } : {}) };
    const r = await fetch(`${this.base}${p}`, { method, headers, body: body !== undefined ? JSON.stringify(body) : undefined, signal: AbortSignal.timeout(10_000) });
    const set = r.headers.get('set-cookie');
    if (set && !/=;/.test(set.split(';')[0] + ';')) this.cookie = set.split(';')[0];
    const text = await r.text();
    let data = null;
    try { data = text ? JSON.parse(text) : null; } catch { data = text; }
    return { status: r.status, data };
  }

  /** GET /api/auth/me as the app does (keeps the cookie renewed). */
  touch() { return this.request('GET', '/api/auth/me'); }
}

/**
 * One /ros socket of a session, as the app's connection (roslib) uses it: subscriptions and advertisements are made
 * again after a reconnect (1 s after a close); service calls time out on the client side.
 */
export class RosLink {
  /** @param {HttpSession} http @param {number} port @param {string} name @param {(s: string) => void} note */
  constructor(http, port, name, note) {
    this.http = http;
    this.port = port;
    this.name = name;
    this.note = note;
    /** @type {WebSocket | null} */
    this.ws = null;
    this.ready = false;
    this.closed = false;
    this.n = 0;
    /** @type {Map<string, {topic: string, type: string, opts: any, cb: (m: any) => void}>} topic -> subscription */
    this.subs = new Map();
    /** @type {Map<string, {type: string, opts: any, id: string}>} */
    this.advs = new Map();
    /** @type {Map<string, {resolve: (r: {ok: boolean, values: any}) => void, timer: any, service: string}>} */
    this.pending = new Map();
    /** @type {(m: any) => void} status messages that answer no pending call */
    this.onStatus = () => {};
    this.reconnects = 0;
    this.closes = 0;
    this.timer = null;
  }

  async open() {
    if (!this.http.cookie) await this.http.login();
    await new Promise((resolve, reject) => {
      const ws = new WebSocket(`ws://127.0.0.1:${this.port}/ros`, { headers: { cookie: this.http.cookie }, perMessageDeflate: false });
      this.ws = ws;
      ws.once('unexpected-response', (req, res) => {
        res.resume();
        req.destroy();
        if (res.statusCode === 401) this.http.cookie = '';
        reject(new Error(`/ros upgrade refused: HTTP ${res.statusCode}`));
      });
      ws.once('open', () => {
        this.ready = true;
        for (const [topic, a] of this.advs) this.#send({ op: 'advertise', id: a.id, type: a.type, topic, latch: false, ...a.opts });
        for (const s of this.subs.values()) this.#sendSub(s);
        resolve(undefined);
      });
      ws.on('message', (d, isBinary) => this.#onMessage(d, isBinary));
      ws.on('error', (e) => { this.note(`${this.name}: socket error ${e.message}`); reject(e); });
      ws.on('close', (code, reason) => {
        const was = this.ready;
        this.ready = false;
        for (const [id, p] of this.pending) { clearTimeout(p.timer); this.pending.delete(id); p.resolve({ ok: false, values: 'socket closed' }); }
        if (this.ws !== ws || this.closed) return;
        if (was) { this.closes++; this.note(`${this.name}: /ros closed ${code} ${reason.toString()}`); }
        this.#reconnectSoon();
      });
    });
  }

  #reconnectSoon() {
    if (this.timer || this.closed) return;
    this.timer = setTimeout(async () => {
      this.timer = null;
      if (this.closed) return;
      try { await this.open(); this.reconnects++; } catch (e) { this.note(`${this.name}: reconnect failed: ${/** @type {Error} */ (e).message}`); this.#reconnectSoon(); }
    }, 1000);
  }

  /** @param {any} m */
  #send(m) {
    if (!this.ready || this.ws?.readyState !== WebSocket.OPEN) return false;
    this.ws.send(JSON.stringify(m));
    return true;
  }

  #sendSub(s) {
    this.#send({ op: 'subscribe', id: `subscribe:${s.topic}:${++this.n}`, type: s.type, topic: s.topic, ...s.opts });
  }

  /** @param {string} topic @param {string} type @param {any} opts compression, throttle_rate, queue_length @param {(m: any) => void} cb */
  subscribe(topic, type, opts, cb) {
    const s = { topic, type, opts, cb };
    this.subs.set(topic, s);
    this.#sendSub(s);
  }

  /** @param {string} topic @param {string} type @param {any} opts */
  advertise(topic, type, opts) {
    const a = { type, opts, id: `advertise:${topic}:${++this.n}` };
    this.advs.set(topic, a);
    this.#send({ op: 'advertise', id: a.id, type, topic, latch: false, ...opts });
  }

  /** @returns {string | null} the publish's id, null when not connected */
  publish(topic, msg) {
    const id = `publish:${topic}:${++this.n}`;
    return this.#send({ op: 'publish', id, topic, msg }) ? id : null;
  }

  /** @param {string} service @param {any} args @param {number} timeoutMs @returns {Promise<{ok: boolean, values: any}>} */
  call(service, args, timeoutMs) {
    const id = `call_service:${service}:${++this.n}`;
    return new Promise((resolve) => {
      if (!this.#send({ op: 'call_service', id, service, args })) { resolve({ ok: false, values: 'not connected' }); return; }
      const timer = setTimeout(() => { this.pending.delete(id); resolve({ ok: false, values: `no answer in ${timeoutMs / 1000} s` }); }, timeoutMs);
      this.pending.set(id, { resolve, timer, service });
    });
  }

  /** @param {Buffer} d @param {boolean} isBinary */
  #onMessage(d, isBinary) {
    let m;
    try { m = isBinary ? cborDecode(d) : JSON.parse(d.toString()); } catch { this.note(`${this.name}: undecodable ${isBinary ? 'CBOR' : 'JSON'} frame`); return; }
    if (m.op === 'publish') {
      this.subs.get(m.topic)?.cb(m.msg);
    } else if (m.op === 'service_response' || (m.op === 'status' && this.pending.has(m.id))) {
      const p = this.pending.get(m.id);
      if (!p) return;
      this.pending.delete(m.id);
      clearTimeout(p.timer);
      p.resolve(m.op === 'status' ? { ok: false, values: m.msg } : { ok: !!m.result, values: m.values });
    } else if (m.op === 'status') {
      this.onStatus(m);
    }
  }

  close() {
    this.closed = true;
    if (this.timer) clearTimeout(this.timer);
    try { this.ws?.close(); } catch { /* gone */ }
  }
}

/** The control lease over HTTP, as the app's ControlLease: take, heartbeat every 500 ms while held, release. */
export class Lease {
  /** @param {HttpSession} http @param {string} name @param {(s: string) => void} note @param {any} win */
  constructor(http, name, note, win) {
    this.http = http;
    this.name = name;
    this.note = note;
    this.win = win;
    this.holds = false;
    this.timer = null;
    this.lastHeartbeatOk = 0;
  }

  /** @param {number} [patienceMs] retry a refusal this long (the other session may be releasing) */
  async take(patienceMs = 5000) {
    const end = now() + patienceMs;
    for (;;) {
      let r;
      try { r = await this.http.request('POST', '/api/control/take', {}); } catch (e) { r = { status: 0, data: { error: /** @type {Error} */ (e).message } }; }
      if (r.status === 200 && r.data?.you) {
        this.holds = true;
        this.win().leaseTakes++;
        this.#beat();
        return true;
      }
      if (now() > end) {
        this.win().leaseRefused++;
        this.note(`${this.name}: control not taken: HTTP ${r.status} ${JSON.stringify(r.data?.error ?? r.data).slice(0, 160)}`);
        return false;
      }
      await sleep(250);
    }
  }

  #beat() {
    clearTimeout(this.timer);
    this.timer = setTimeout(async () => {
      if (!this.holds) return;
      let r;
      try { r = await this.http.request('POST', '/api/control/heartbeat', {}); } catch (e) { r = { status: 0, data: { error: /** @type {Error} */ (e).message } }; }
      if (!this.holds) return;
      if (r.status === 200 && r.data?.you) this.lastHeartbeatOk = now();
      else if (r.status === 409) {
        this.holds = false;
        this.win().leaseLost++;
        this.note(`${this.name}: lost control: ${JSON.stringify(r.data).slice(0, 200)}`);
        return;
      } else this.note(`${this.name}: heartbeat HTTP ${r.status} ${JSON.stringify(r.data).slice(0, 120)}`);
      this.#beat();
    }, 500);
  }

  async release() {
    const was = this.holds;
    this.holds = false;
    clearTimeout(this.timer);
    if (!was) return;
    try {
      const r = await this.http.request('POST', '/api/control/release', {});
      if (r.status !== 204) this.note(`${this.name}: release HTTP ${r.status}`);
    } catch (e) { this.note(`${this.name}: release ${/** @type {Error} */ (e).message}`); }
  }
}

/** The Cameras page: one stream, CBOR, newest frame only. */
export class CameraViewer {
  /** @param {RosLink} link @param {string} topic @param {() => any} win */
  constructor(link, topic, win) {
    this.link = link;
    this.topic = topic;
    this.win = win;
    this.lastAt = 0;
    this.frames = 0;
  }

  start() {
    this.link.subscribe(this.topic, 'sensor_msgs/CompressedImage', { compression: 'cbor', throttle_rate: 33, queue_length: 1 }, (msg) => {
      const t = now();
      const w = this.win();
      const d = msg?.data;
      const ok = d instanceof Uint8Array && d.length > 2 && d[0] === 0xff && d[1] === 0xd8;
      if (!ok) { w.camBad++; return; }
      if (w.camFrames && t - this.lastAt > w.camMaxGapMs) w.camMaxGapMs = t - this.lastAt;
      w.camFrames++;
      w.camBytes += d.length;
      this.lastAt = t;
      this.frames++;
    });
  }
}

/** A jog moved the arm: the joint travelled more than this (a 1 s jog at half speed: ~0.2-0.5 rad; a loaded host
 * delays the 50 ms heartbeats past the driver's 0.2 s timeout and the jog stutters, see the minimum per minute). */
export const MOVED_RAD = 0.005;
const START_WAIT_MS = 5000;

/** The Manual page of one motion group (an admin): state, jog, moves. */
export class ManualSession {
  /** @param {RosLink} link @param {any} cell the cell file @param {(s: string) => void} note @param {() => any} win */
  constructor(link, cell, note, win) {
    this.link = link;
    this.cell = cell;
    this.note = note;
    this.win = win;
    this.group = cell.manual.groups[0].name;
    this.home = cell.manual.groups[0].configurations?.home ?? null;
    /** @type {any} the driver's latest RobotState */
    this.state = null;
    this.stateAt = 0;
    this.refusals = [];
  }

  async open() {
    this.link.onStatus = (m) => {
      if (String(m.id || '').startsWith('publish:/cell/manual/jog')) this.refusals.push(String(m.msg));
      else if (m.level === 'error') this.note(`manual: status ${String(m.msg).slice(0, 160)}`);
    };
    this.link.subscribe(`/cell/manual/${this.group}/state`, 'cell_msgs/RobotState', {}, (m) => {
      this.state = m;
      this.stateAt = now();
      const text = String(m?.message);
      // A heartbeat that reached the driver later than the jog timeout is dropped (a jog's motion may pause): counted,
      // not a refusal (the arm's travel tells whether the jog moved it).
      if (/^jog ignored: it arrived/.test(text)) { if (text !== this.lastLate) this.win().jogLate++; this.lastLate = text; }
      else if (/^jog (refused|ignored)/.test(text)) this.lastDriverRefusal = text;
    });
    this.link.advertise('/cell/manual/jog', 'cell_msgs/JogCommand', { queue_size: 1 });
    const r = await this.link.call('/cell/manual/groups', {}, 5000);
    if (!r.ok) this.note(`manual: /cell/manual/groups failed: ${JSON.stringify(r.values).slice(0, 160)}`);
  }

  q() { return Array.isArray(this.state?.joint_positions) ? [...this.state.joint_positions] : null; }

  /**
   * One hold-to-run jog of a joint: the command at once and every 50 ms, held for holdMs once the arm moves, as an
   * operator holds the button (the first motion after the control script (re)starts waits for it: up to
   * START_WAIT_MS); then direction 0; the arm's travel read from the driver's state once it stopped.
   * @returns {Promise<{moved: boolean, travel: number, why: string}>}
   */
  async jog(axis, direction, holdMs, fraction = 0.5) {
    const q0 = this.q();
    const msg = { group: this.group, mode: 'joint', axis, direction, speed: fraction, frame: 'base' };
    this.refusals = [];
    this.lastDriverRefusal = '';
    const t0 = now();
    let sent = 0;
    let k = 0;
    let movedAt = 0;
    while (movedAt ? now() - movedAt < holdMs : now() - t0 < START_WAIT_MS) {
      if (!movedAt) {
        const q = this.q();
        if (q0 && q && Math.abs(q[axis] - q0[axis]) > MOVED_RAD) movedAt = now();
      }
      if (this.link.publish('/cell/manual/jog', msg)) sent++;
      k++;
      await sleep(Math.max(0, t0 + k * 50 - now()));
    }
    this.link.publish('/cell/manual/jog', { ...msg, direction: 0 });
    await sleep(500); // the arm decelerates; the state (20 Hz) catches up
    const q1 = this.q();
    const travel = q0 && q1 ? Math.abs(q1[axis] - q0[axis]) : NaN;
    const w = this.win();
    let why = '';
    if (!sent) why = 'not connected';
    else if (this.refusals.length) why = `refused by the BFF: ${this.refusals[0].slice(0, 160)}`;
    else if (this.lastDriverRefusal) why = `refused by the driver: ${this.lastDriverRefusal.slice(0, 160)}`;
    else if (!(travel > MOVED_RAD)) why = `the arm did not move (${Number.isFinite(travel) ? travel.toFixed(4) : '?'} rad)`;
    if (why) { w.jogRefused++; this.note(`jog ${axis + 1} ${direction > 0 ? '+' : '-'}: ${why}`); } else { w.jogOk++; w.jogTravel.push(travel); }
    this.lastJog = { moved: !why, travel, why, at: now() };
    return this.lastJog;
  }

  /** A service move or tool action as the page's buttons call it; false (noted) when it failed. */
  async call(service, args, what) {
    const r = await this.link.call(service, args, 120_000);
    const ok = r.ok && r.values?.success !== false;
    if (!ok) this.note(`manual: ${what} failed: ${JSON.stringify(r.values?.message ?? r.values).slice(0, 200)}`);
    return ok;
  }

  movePose(pose, speed, what) { return this.call('/cell/manual/move_pose', { group: this.group, pose, speed, acceleration: 1.0 }, what); }
  tool(action) { return this.call('/cell/manual/tool', { tool: 'gripper', action }, `gripper ${action}`); }
  moveHome() { return this.call('/cell/manual/move_named', { group: this.group, name: 'home', speed: 1.0, acceleration: 1.5 }, 'move home'); }
}

/** The Process page of an operator. */
export class ProcessSession {
  /** @param {RosLink} link @param {any} cell @param {(s: string) => void} note @param {() => any} win */
  constructor(link, cell, note, win) {
    this.link = link;
    this.cell = cell;
    this.note = note;
    this.win = win;
    /** @type {any} */
    this.state = null;
    this.lastCycle = 0;
    this.lastCycleAt = 0;
    this.cyclesTotal = 0;
    /** @type {(entry: number) => void} a cycle using pose-table entry `entry` completed */
    this.onCycle = () => {};
    this.logSeen = 0;
  }

  open() {
    this.link.onStatus = (m) => { if (m.level === 'error') this.note(`process: status ${String(m.msg).slice(0, 160)}`); };
    this.link.subscribe('/cell/process/state', 'cell_msgs/ProcessState', {}, (m) => this.#onState(m));
    this.link.subscribe('/cell/process/log', 'cell_msgs/LogEntries', {}, (m) => this.#onLog(m));
    const fieldTopics = [...new Set((this.cell.process.status_fields || []).map((f) => f.topic))].filter((t) => t !== '/cell/process/state');
    for (const t of fieldTopics) this.link.subscribe(t, '', { throttle_rate: 200, queue_length: 1 }, () => {});
  }

  #onState(m) {
    this.state = m;
    const c = Number(m?.cycle);
    if (!Number.isFinite(c) || c < 1) return;
    if (this.lastCycle && c > this.lastCycle) {
      const n = this.cycleTableLength();
      for (let done = this.lastCycle; done < c; done++) {
        this.cyclesTotal++;
        this.win().cycles++;
        if (m.last_cycle_s > 0) this.win().cycleTimes.push(Number(m.last_cycle_s));
        this.onCycle((done - 1) % n);
      }
      this.lastCycleAt = now();
    }
    this.lastCycle = c;
  }

  #onLog(m) {
    const entries = Array.isArray(m?.entries) ? m.entries : [];
    // Latched, the last 200: only the entries newer than the newest seen.
    const stamp = (e) => Number(e?.stamp?.secs ?? 0) * 1e3 + Number(e?.stamp?.nsecs ?? 0) / 1e6;
    for (const e of entries) {
      const t = stamp(e);
      if (t <= this.logSeen) continue;
      this.logSeen = t;
      if (e.level === 'error') { this.win().processLogErrors++; this.note(`process log: ${String(e.text).slice(0, 200)}`); }
    }
  }

  cycleTableLength() {
    const poses = this.cell.process.poses || {};
    return Math.max(1, ...Object.values(poses).map((t) => (Array.isArray(t) ? t.length : 1)));
  }

  /** Start as the page calls it (8 s timeout). @returns {Promise<'ok' | 'refused' | 'no answer'>} */
  async start(cycles) {
    const r = await this.link.call('/cell/process/start', { cycles }, 8000);
    if (r.ok && r.values?.success !== false) return 'ok';
    const noAnswer = /^no answer/.test(String(r.values));
    this.note(`process: Start ${noAnswer ? 'not answered' : 'refused'}: ${JSON.stringify(r.values?.message ?? r.values).slice(0, 200)}`);
    return noAnswer ? 'no answer' : 'refused';
  }

  /** Until the run is over (or `ms`). */
  async waitIdle(ms) {
    const end = now() + ms;
    while (this.active() && now() < end) await sleep(200);
    return !this.active();
  }

  async stop() {
    const r = await this.link.call('/cell/process/stop', {}, 8000);
    if (!(r.ok && r.values?.success !== false)) this.note(`process: Stop failed: ${JSON.stringify(r.values?.message ?? r.values).slice(0, 200)}`);
  }

  active() { return ['running', 'pausing', 'paused', 'stopping'].includes(this.state?.state); }
}

/**
 * The cell's day: one arm, one lease. The process runs until the fixture is full (up to the pose tables' length
 * in cycles, 3 on the demo cell); then the manual session takes control, jogs and puts the parts back where the
 * process picks them; then the process again. See soak_bench.mjs's header for why.
 */
export class CellSchedule {
  /** @param {{manual: ManualSession, process: ProcessSession, jogLease: Lease, processLease: Lease, cell: any, note: (s: string) => void, win: () => any, feeder: () => Promise<{ok: boolean, message: string}>, jogPairs?: number}} o */
  constructor(o) {
    Object.assign(this, o);
    this.jogPairs = o.jogPairs ?? 2;
    this.stopping = false;
    /** pose-table entries whose part sits in the fixture */
    this.inFixture = new Set();
    this.process.onCycle = (e) => this.inFixture.add(e);
    this.errorsInARow = 0;
    /** a run failed since the last restock */
    this.afterError = false;
    this.gaveUp = false;
    this.pairN = 0;
    this.phase = 'idle';
    const ah = (o.cell.parameters?.items || []).find((i) => i.id === 'approach_height');
    this.approach = (ah?.default ?? 100) / 1000;
  }

  /** Waits for the driver and the process server. @param {number} timeoutMs @param {() => boolean} [cancelled] */
  async ready(timeoutMs, cancelled = () => false) {
    const end = now() + timeoutMs;
    while (now() < end && !cancelled()) {
      if (this.manual.state?.connected && this.process.state?.ready && this.process.state.state === 'idle' && this.manual.q()) return true;
      await sleep(250);
    }
    if (cancelled()) return false;
    throw new Error(`the cell is not ready after ${timeoutMs / 1000} s: driver ${JSON.stringify({ connected: this.manual.state?.connected, message: this.manual.state?.message })}, process ${JSON.stringify({ ready: this.process.state?.ready, state: this.process.state?.state, message: this.process.state?.message })}`);
  }

  async run() {
    // The manual session first (jogs from the first minute on), then the process, in turn.
    while (!this.stopping) {
      await this.manualPhase();
      if (this.stopping) break;
      const n = this.process.cycleTableLength();
      const entry = ((this.process.state?.cycle ?? 1) - 1) % n;
      if (!this.gaveUp && !(entry === 0 && this.inFixture.size)) await this.processPhase(n - entry);
      else await sleep(1000);
    }
  }

  async processPhase(cycles) {
    this.phase = 'process';
    if (!(await this.processLease.take())) return;
    try {
      if (this.stopping) return;
      const before = this.process.cyclesTotal;
      const started = await this.process.start(cycles);
      if (started === 'refused' && !this.process.active()) { this.#error(); return; }
      // The state shows the run (on a loaded host it lags behind the answer; and a Start that got no answer in
      // 8 s may start the run all the same). Watched whatever else happens: nobody else may take control while a
      // run could still start.
      const shown = now() + 20_000;
      while (!this.process.active() && this.process.cyclesTotal === before && now() < shown) await sleep(200);
      if (!this.process.active() && this.process.cyclesTotal === before) {
        this.note(`process: ${started === 'ok' ? 'Start answered, but the state never showed the run' : 'no run after the unanswered Start'}`);
        this.#error();
        return;
      }
      if (started !== 'ok') this.note('process: the Start that got no answer in 8 s started the run after all');
      this.win().runs++;
      // Wait for the run to end (done, error), at most 90 s a cycle.
      const end = now() + cycles * 90_000;
      while (!this.stopping && this.process.active() && now() < end) await sleep(200);
      if (this.stopping) return;
      if (this.process.active()) { this.note(`process: a run of ${cycles} cycles still going after ${cycles * 90} s: stopping it`); await this.process.stop(); this.#error(); return; }
      if (this.process.state?.state === 'error') { this.note(`process: run ended in error: ${String(this.process.state.message).slice(0, 200)}`); this.#error(); return; }
      if (this.process.cyclesTotal > before) this.errorsInARow = 0;
    } finally {
      await this.processLease.release();
    }
  }

  #error() {
    this.win().processErrors++;
    this.afterError = true;
    if (++this.errorsInARow >= 3 && !this.gaveUp) { this.gaveUp = true; this.note('process: 3 failed runs in a row: no more Starts (the jogging goes on)'); }
  }

  async manualPhase() {
    this.phase = 'manual';
    if (!(await this.jogLease.take())) { await sleep(1000); return; }
    try {
      await this.clear();
      await this.jogWindow(this.jogPairs);
      if (this.stopping) return;
      const full = this.inFixture.size && ((this.process.state?.cycle ?? 1) - 1) % this.process.cycleTableLength() === 0;
      if (full || this.afterError) await this.restock(); // after a failed run a part may lie anywhere
    } finally {
      await this.jogLease.release();
    }
  }

  /**
   * Before jogging: an arm away from home (a process stopped or failed mid-cycle: the gripper may be down in a
   * pocket) goes straight up by the approach height when it is low over the table, then home, as an operator would
   * (swinging the base with the fingers around a part in the fixture ends in a protective stop).
   */
  async clear() {
    const q = this.manual.q();
    const home = this.manual.home;
    if (!q || !home || Math.max(...home.map((h, i) => Math.abs(q[i] - h))) < 0.05) return;
    const p = this.manual.state?.tcp_pose;
    if (Array.isArray(p) && p.length === 6 && p[2] < 0.15) await this.manual.movePose([p[0], p[1], p[2] + this.approach, p[3], p[4], p[5]], 0.1, 'retract before jogging');
    await this.manual.moveHome();
    this.win().homed++;
  }

  /** Joint 1 (the base) back and forth: + then - (or - then +, alternately), 1 s each, as a thumb on the page. */
  async jogWindow(pairs) {
    for (let i = 0; i < pairs && !this.stopping; i++) {
      const first = this.pairN++ % 2 === 0 ? 1 : -1;
      await this.manual.jog(0, first, 1000);
      await sleep(300);
      await this.manual.jog(0, -first, 1000);
      await sleep(700);
    }
  }

  /**
   * The fixture is full: the feeder puts the parts back where the process picks them (the sim's /sim/restock, as
   * a feeder or an operator refilling a real cell would; earlier soaks did it with the arm, whose set-down was only
   * as exact as a teach-by-numbers grasp, and a part set down a few millimetres off ended in a force alarm later).
   */
  async restock() {
    this.phase = 'restock';
    const r = await this.feeder();
    if (r.ok) { this.win().restocked += this.inFixture.size; } else {
      this.win().restockErrors++;
      this.note(`restock: ${r.message}`);
    }
    this.inFixture.clear();
    this.afterError = false;
    return r.ok;
  }

  /**
   * The end of the soak: the operator stops the process if it runs (Stop needs no lease), the manual session takes
   * control and jogs once more. @returns {Promise<{took: boolean, jog: any}>}
   */
  async finish(runP) {
    this.stopping = true;
    if (this.process.active()) await this.process.stop();
    await Promise.race([runP, sleep(150_000)]); // a move under way ends (a restock step: seconds)
    // (A Start answered late may have started the run meanwhile: stopped too, and over, before anyone jogs.)
    for (let i = 0; i < 3 && this.process.active(); i++) { await this.process.stop(); await this.process.waitIdle(10_000); }
    await this.processLease.release();
    const took = this.jogLease.holds || (await this.jogLease.take(10_000));
    let jog = null;
    if (took) {
      await this.clear();
      const first = this.pairN % 2 === 0 ? 1 : -1;
      await this.manual.jog(0, first, 1000);
      await sleep(300);
      jog = await this.manual.jog(0, -first, 1000);
      await this.jogLease.release();
    }
    return { took, jog };
  }
}

/** A process of the stack as named in the figures: its ROS node name, else what it runs. */
export function procName(pid) {
  let argv;
  try { argv = fs.readFileSync(`/proc/${pid}/cmdline`, 'latin1').split('\0').filter(Boolean); } catch { return null; }
  const node = argv.find((a) => a.startsWith('__name:='));
  if (node) return node.slice('__name:='.length);
  const js = argv.find((a) => /\.m?js$/.test(a));
  if (js) return js.endsWith('bff/src/server.js') ? 'bff' : path.basename(js).replace(/\.m?js$/, '');
  const m = argv.indexOf('-m');
  if (m >= 0 && argv[m + 1]) return argv[m + 1];
  const c = argv.indexOf('-c');
  if (c >= 0 && /multiprocessing\.spawn/.test(argv[c + 1] || '')) return 'sim renderer';
  if (c >= 0 && /resource_tracker/.test(argv[c + 1] || '')) return 'sim resource_tracker'; // (only the sim uses multiprocessing)
  // A python script (roscore, rosmaster, roslaunch): the script's name; else the program's.
  const script = /python/.test(path.basename(argv[0] || '')) ? argv.find((a, i) => i > 0 && !a.startsWith('-')) : null;
  return path.basename(script || argv[0] || String(pid));
}

/** VmRSS and its private (anonymous) part, kB: file-backed pages (the program's own code paged in as new paths run)
 * count in RSS but are not memory the process holds on to. @returns {[number, number]} */
const memKb = (pid) => {
  try {
    const st = fs.readFileSync(`/proc/${pid}/status`, 'utf8');
    return [Number(/VmRSS:\s+(\d+)/.exec(st)[1]), Number(/RssAnon:\s+(\d+)/.exec(st)[1])];
  } catch { return [NaN, NaN]; }
};
/** CPU time of a process so far, in clock ticks (1/100 s), NaN once it is gone. @param {number} pid */
export const cpuTicks = (pid) => { try { const s = fs.readFileSync(`/proc/${pid}/stat`, 'utf8'); const f = s.slice(s.lastIndexOf(') ') + 2).split(' '); return Number(f[11]) + Number(f[12]); } catch { return NaN; } };

/** Every process of one stack (pidsOfStack), grouped by name: RSS samples per minute, CPU, restarts. */
/**
 * The sim's feeder: /sim/restock over rosbridge itself, not through the BFF (it is the world's, not a user's).
 * @param {number} rosbridgePort @returns {() => Promise<{ok: boolean, message: string}>}
 */
export function simFeeder(rosbridgePort) {
  return () => new Promise((resolve) => {
    const ws = new WebSocket(`ws://127.0.0.1:${rosbridgePort}`);
    const done = (/** @type {{ok: boolean, message: string}} */ r) => { clearTimeout(timer); ws.close(); resolve(r); };
    const timer = setTimeout(() => done({ ok: false, message: '/sim/restock did not answer within 10 s' }), 10_000);
    ws.once('open', () => ws.send(JSON.stringify({ op: 'call_service', id: 'restock', service: '/sim/restock' })));
    ws.on('message', (d) => {
      const m = JSON.parse(d.toString());
      if (m.op === 'service_response' && m.id === 'restock') done({ ok: m.result === true && m.values?.success === true, message: String(m.values?.message ?? m.values) });
    });
    ws.once('error', (e) => done({ ok: false, message: `rosbridge: ${e.message}` }));
  });
}

export class ProcWatch {
  /** @param {string} dataDir @param {(s: string) => void} note */
  constructor(dataDir, note) {
    this.dataDir = dataDir;
    this.note = note;
    /** @type {Map<string, string>} name -> sorted pids, as last seen */
    this.pidsOf = new Map();
    /** @type {Map<string, number[]>} this minute's RSS samples (MiB) */
    this.samples = new Map();
    /** @type {Map<string, number[]>} this minute's RssAnon samples (MiB) */
    this.anon = new Map();
    /** @type {Map<number, number>} CPU ticks at the minute's start (or when first seen) */
    this.ticks0 = new Map();
    this.restarts = new Map();
    this.gone = new Map();
    this.appeared = new Map();
    this.baseline = false;
  }

  /** @returns {Map<string, number[]>} name -> pids */
  groups() {
    const g = new Map();
    for (const pid of pidsOfStack(this.dataDir)) {
      const name = procName(pid);
      if (!name) continue;
      if (!g.has(name)) g.set(name, []);
      g.get(name).push(pid);
    }
    return g;
  }

  /** The start: what runs now is the stack (later arrivals are noted). */
  start(minute = 0) {
    const g = this.groups();
    for (const [name, pids] of g) {
      this.pidsOf.set(name, pids.slice().sort().join(','));
      for (const p of pids) this.ticks0.set(p, cpuTicks(p));
    }
    this.baseline = true;
    this.minute = minute;
    return g;
  }

  /** @param {number} minute the minute this sample belongs to */
  sample(minute) {
    const g = this.groups();
    for (const [name, pids] of g) {
      const key = pids.slice().sort().join(',');
      const was = this.pidsOf.get(name);
      if (was === undefined) {
        this.appeared.set(name, minute);
        this.note(`process ${name} appeared (pid ${key})`);
      } else if (was !== key) {
        const old = new Set(was.split(','));
        const lost = [...old].filter((p) => p && !pids.includes(Number(p)));
        if (lost.length) { this.restarts.set(name, (this.restarts.get(name) || 0) + 1); this.note(`process ${name}: pid ${was} -> ${key} (restarted)`); }
      }
      this.pidsOf.set(name, key);
      for (const p of pids) if (!this.ticks0.has(p)) this.ticks0.set(p, 0);
      const mem = pids.map(memKb).filter(([r]) => Number.isFinite(r));
      if (!this.samples.has(name)) { this.samples.set(name, []); this.anon.set(name, []); }
      this.samples.get(name).push(mem.reduce((a, [r]) => a + r, 0) / 1024);
      this.anon.get(name).push(mem.reduce((a, [, an]) => a + an, 0) / 1024);
    }
    for (const [name, key] of this.pidsOf) {
      if (!g.has(name) && key !== '') {
        this.gone.set(name, minute);
        this.note(`process ${name} (pid ${key}) is gone`);
        this.pidsOf.set(name, '');
      }
    }
  }

  /** The minute's figures per process: RSS median and max (MiB), CPU % of one core. @param {number} elapsedS */
  endMinute(elapsedS) {
    const out = {};
    for (const [name, xs] of this.samples) {
      const pids = (this.pidsOf.get(name) || '').split(',').filter(Boolean).map(Number);
      let ticks = 0;
      for (const p of pids) {
        const t = cpuTicks(p);
        if (Number.isFinite(t)) { ticks += t - (this.ticks0.get(p) ?? 0); this.ticks0.set(p, t); }
      }
      out[name] = { rssMiB: median(xs), rssMaxMiB: Math.max(...xs), anonMiB: median(this.anon.get(name) || []),
        cpuPct: ((ticks / 100) / elapsedS) * 100, pids: pids.length };
    }
    this.samples = new Map();
    this.anon = new Map();
    return out;
  }
}

// Error lines: the brief's list (Traceback, ERROR, "[bff] error", uncaught, exited) plus roslaunch's "process has died"
// and FATAL. Case-sensitive ERROR/FATAL (log levels), not every "error" in a message.
const ERROR_RES = [/Traceback \(most recent call last\)/, /\bERROR\b/, /\bFATAL\b/, /^\[bff\].*\berror\b/i, /uncaught|unhandled/i, /\bexited\b/, /process has died/];
export const isErrorLine = (l) => ERROR_RES.some((re) => re.test(l));

/** Error lines in the stack's output and in its ROS log files, written after mark(); read on as they grow. */
export class LogWatch {
  /** @param {{output: () => string}} stack @param {string} dataDir */
  constructor(stack, dataDir) {
    this.stack = stack;
    this.logDir = path.join(dataDir, 'ros', 'log');
    this.outAt = 0;
    this.markAt = 0;
    /** @type {Map<string, number>} file -> bytes read (whole lines only) */
    this.at = new Map();
    this.marked = false;
    /** @type {{source: string, line: string, detail: string}[]} every error line since mark() */
    this.found = [];
  }

  /** Every .log file under the ROS log directory, symlinks (`latest`) not followed. rosout.log is left out: it
   * repeats what every node writes to its own file. */
  files() {
    const out = [];
    const walk = (d) => {
      let ents = [];
      try { ents = fs.readdirSync(d, { withFileTypes: true }); } catch { return; }
      for (const e of ents) {
        const p = path.join(d, e.name);
        if (e.isDirectory()) walk(p);
        else if (e.isFile() && e.name.endsWith('.log') && e.name !== 'rosout.log') out.push(p);
      }
    };
    walk(this.logDir);
    return out;
  }

  /** From here on error lines count (the start-up is over). */
  mark() {
    const out = this.stack.output();
    this.outAt = this.markAt = out.lastIndexOf('\n') + 1;
    for (const f of this.files()) { try { this.at.set(f, fs.statSync(f).size); } catch { /* gone */ } }
    this.marked = true;
  }

  /** Error lines of the stack's output before mark(), the start-up (its ROS logs: not read). */
  startup() { return LogWatch.scanText(this.stack.output().slice(0, this.markAt), 'stack.log', true); }

  /** @param {string} text @param {string} source @param {boolean} prefixed lines start with "[name] " */
  static scanText(text, source, prefixed) {
    const lines = text.split('\n');
    const found = [];
    for (let i = 0; i < lines.length; i++) {
      const l = lines[i];
      if (!isErrorLine(l)) continue;
      let detail = '';
      if (/Traceback/.test(l)) {
        // The exception: the first line after the frames (indented) and "During handling ..." lines.
        for (let j = i + 1; j < Math.min(lines.length, i + 60); j++) {
          const body = prefixed ? lines[j].replace(/^\[[^\]]+\] ?/, '') : lines[j];
          if (!body.trim() || /^\s/.test(body) || /^(Traceback|During handling|The above exception)/.test(body)) continue;
          detail = body.trim();
          break;
        }
      }
      found.push({ source, line: l.trim(), detail });
    }
    return found;
  }

  /** The error lines written since the last call (whole lines only; a traceback's exception line may come a call
   * later than its "Traceback" line: then `detail` stays empty). */
  scanNew() {
    if (!this.marked) return [];
    const fresh = [];
    const out = this.stack.output();
    const upTo = out.lastIndexOf('\n') + 1;
    if (upTo > this.outAt) {
      fresh.push(...LogWatch.scanText(out.slice(this.outAt, upTo), 'stack.log', true));
      this.outAt = upTo;
    }
    for (const f of this.files()) {
      let from = this.at.get(f) ?? 0;
      let size;
      try { size = fs.statSync(f).size; } catch { continue; }
      if (size < from) from = 0;
      if (size === from) continue;
      const buf = Buffer.alloc(size - from);
      const fd = fs.openSync(f, 'r');
      try { fs.readSync(fd, buf, 0, buf.length, from); } finally { fs.closeSync(fd); }
      const end = buf.lastIndexOf(10) + 1;
      if (!end) continue;
      this.at.set(f, from + end);
      fresh.push(...LogWatch.scanText(buf.subarray(0, end).toString('utf8'), path.relative(this.logDir, f).replace(/^[0-9a-f-]{36}\//, ''), false));
    }
    this.found.push(...fresh);
    return fresh;
  }
}
