#!/usr/bin/env node
// `npm start`: roscore (unless ROS_MASTER_URI answers), the simulated cell, the ROS side and the BFF.
// Every child runs in its own process group and carries a stack marker in its environment, so Ctrl-C
// stops all of them (roslaunch's nodes live in their own sessions) within 5 s and leaves nothing behind.
// A watchdog (scripts/watchdog.js, detached) stops them too if this supervisor dies, even by SIGKILL.
//
// Supervision: a child that dies without being asked to is restarted with the same command after a back-off
// (scripts/supervise/restart-policy.js: at once, then 0.5 s doubling to 10 s), once whatever is left of it is gone: its
// process group and every process carrying its own marker (CELL_STACK_CHILD=<name>: roslaunch's nodes
// outlive a SIGKILLed roslaunch, and an old rosbridge would hold the port). When roscore dies, the ROS side
// and the simulated cell are stopped too and started again once the new master answers (rospy nodes never
// re-register with a new master). An external master (one we did not start) is never restarted. A crash
// loop (5 crashes of one child within 60 s) ends the stack with exit code 1, a configuration error (a child
// exits with 2) at once with exit code 2: whatever runs the stack (systemd) decides what comes next.
// A BFF that runs but no longer answers /api/health (a blocked event loop) for LIVENESS_TIMEOUT_S (30 s; 0: off)
// after it first answered is killed, and so restarted like one that died (scripts/supervise/liveness.js).
import { spawn } from 'node:child_process';
import crypto from 'node:crypto';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import v8 from 'node:v8';
import vm from 'node:vm';
import { readEnv, REPO_ROOT } from '../bff/src/core/config/env.js';
import { loadCell, CellConfigError } from '../bff/src/core/config/cell.js';
import { FEATURES } from '../bff/src/features/index.js';
import { launchFiles } from './feature-launch.js';
import { masterOnline, tcpReachable } from '../bff/src/core/ros/health.js';
import { resolveHosts, armsOf } from '../bff/src/core/config/hosts.js';
import { RestartPolicy, restartDelay, seconds } from './supervise/restart-policy.js';
import { Liveness, graceFromEnv } from './supervise/liveness.js';
import { fdOutput } from './supervise/output.js';

const env = readEnv();
const urHost = process.env.UR_HOST || '127.0.0.1'; // the UR controller, or where the simulated one listens
const STACK_ID = crypto.randomUUID();
const rosHome = path.join(env.dataDir, 'ros');
fs.mkdirSync(rosHome, { recursive: true });
const masterPort = Number(new URL(env.rosMasterUri).port || 11311);
// Never process.stdout / console: a stalled reader of a pipe would block the supervisor (supervise/output.js).
const out = fdOutput(1, { onError: () => shutdown(1) });
const err = fdOutput(2, { onError: () => { /* stderr gone: stdout still says what happens */ } });
const log = (m) => out.line(`[stack] ${m}`);

const childEnv = {
  ...process.env,
  CELL_STACK_ID: STACK_ID,
  ROS_MASTER_URI: env.rosMasterUri,
  ROSBRIDGE_PORT: String(env.rosbridgePort),
  CELL_CONFIG: env.cellConfig,
  DATA_DIR: env.dataDir,
  USERS_FILE: env.usersFile,
  UR_HOST: urHost,
  PORT: String(env.port),
  TLS_PORT: String(env.tlsPort),
  ROS_HOME: process.env.ROS_HOME || rosHome,
  ROS_LOG_DIR: process.env.ROS_LOG_DIR || path.join(rosHome, 'log'),
  ROS_HOSTNAME: process.env.ROS_HOSTNAME || '127.0.0.1',
};

/** Children that hold registrations with the master: started again after a new roscore. */
const MASTER_DEPENDENTS = ['ros', 'sim'];
/** A child exiting with this code found a configuration error (bad cell or users file): restarting cannot help. */
const CONFIG_ERROR = 2;
/** After SIGTERM, how long what is left of a dead child (or a dependent of a dead master) gets before SIGKILL. */
const CLEANUP_GRACE_MS = 1500;
const KILL_WAIT_MS = 3000;  // after SIGKILL, for what clearChild cleared

/**
 * One supervised child: its command, its current process (null while it is down) and its restart policy.
 * `gen` is bumped whenever a pending restart must be dropped (a newer one, or roscore's); `held` marks a
 * dependent of the master waiting for the new roscore.
 * @typedef {{name: string, cmd: string, args: string[], proc: import('node:child_process').ChildProcess | null,
 *   policy: RestartPolicy, gen: number, held: boolean}} Child
 */
/** @type {Map<string, Child>} in start order */
const children = new Map();
let stopping = false;
/** roscore died and its restart (and its dependents') is under way. */
let coreDown = false;
/** Resolved by shutdown: every back-off wait ends at once. @type {Set<() => void>} */
const wakers = new Set();

// The watchdog runs in its own session and holds the read end of a pipe whose write end only this process
// has: when the supervisor dies, however it dies, the watchdog sees EOF and stops every process of the stack
// (child groups and marked processes). It starts before the first child and learns each child's group as it
// starts (restarts included); a child spawned at the moment of a SIGKILL is still found by its marker.
// After a clean shutdown, `done` + EOF make it check that nothing is left and exit.
const WATCHDOG = fileURLToPath(new URL('./watchdog.js', import.meta.url));
/** @type {import('node:child_process').ChildProcess | null} */
let watchdog = null;
let watchdogRestarts = 0;

function startWatchdog() {
  const groups = [...children.values()].filter((c) => c.proc?.pid && !exited(c.proc)).map((c) => String(c.proc?.pid));
  // --jitless: it idles for hours on a 250 ms timer; after ~5 minutes V8 would compile Node's timer code with
  // Turbofan, paging in the compiler and growing its RSS by 13 % (43 -> 49 MiB, seen in the soak), for no gain.
  // Its stderr is ours, but never by inheriting our descriptor: a child's start-up puts its stdio back in blocking
  // mode, and on a shared pipe that is ours too (our writes would block again: supervise/output.js). A pipe or file
  // reopened through /proc is a descriptor of its own; a socket cannot be: then its lines are relayed (and its last
  // ones lost if we die).
  let wdErr;
  try { wdErr = fs.openSync('/proc/self/fd/2', fs.constants.O_WRONLY | fs.constants.O_APPEND); } catch { wdErr = 'pipe'; }
  const wd = spawn(process.execPath, ['--jitless', WATCHDOG, STACK_ID, String(process.pid), ...groups],
    { detached: true, stdio: ['pipe', 'ignore', wdErr] });
  if (typeof wdErr === 'number') fs.closeSync(wdErr);
  else if (wd.stderr) relay('watchdog', wd.stderr, err);
  wd.stdin.on('error', () => { /* it died: see 'exit' */ });
  wd.on('error', (e) => log(`watchdog: ${e.message}`));
  wd.on('exit', (code, sig) => {
    if (stopping || wd !== watchdog) return;
    if (++watchdogRestarts > 5) { log(`warning: the watchdog exited (${sig || code}) again; running without one`); return; }
    log(`the watchdog exited (${sig || code}); restarting it`);
    watchdog = startWatchdog();
  });
  return wd;
}

/** Tell the watchdog about a child group (`group`), or that one is gone for good (`forget`). */
function tellWatchdog(cmd, pid) {
  if (pid && watchdog?.stdin?.writable) watchdog.stdin.write(`${cmd} ${pid}\n`);
}

/** After a clean shutdown: let the watchdog check that nothing is left, and wait for it to exit. */
async function stopWatchdog(ms) {
  const wd = watchdog;
  if (!wd || exited(wd)) return;
  const gone = new Promise((r) => wd.once('exit', r));
  if (wd.stdin.writable) wd.stdin.end('done\n');
  await Promise.race([gone, new Promise((r) => setTimeout(r, ms))]);
}

/** Start a command inside the ROS environment (scripts/ros-env.sh). */
function startRos(name, command) {
  return start(name, 'bash', ['-c', `source scripts/ros-env.sh && exec ${command}`]);
}

/** Register a child and start it (or hold it, for a dependent of a master being restarted). */
function start(name, cmd, args) {
  /** @type {Child} */
  const c = { name, cmd, args, proc: null, policy: new RestartPolicy(), gen: 0, held: false };
  children.set(name, c);
  if (coreDown && MASTER_DEPENDENTS.includes(name)) c.held = true;
  else spawnChild(c);
  return c;
}

/** @param {Child} c */
function spawnChild(c) {
  if (stopping) return;
  if (!watchdog) watchdog = startWatchdog();
  const { name } = c;
  const proc = spawn(c.cmd, c.args, {
    cwd: REPO_ROOT, env: { ...childEnv, CELL_STACK_CHILD: name }, detached: true, stdio: ['ignore', 'pipe', 'pipe'],
  });
  relay(name, proc.stdout, out);
  relay(name, proc.stderr, err);
  proc.on('error', (e) => {
    log(`${name}: ${e.message}`);
    if (!proc.pid) onExit(c, proc, null, 'spawn failed'); // no 'exit' comes for a process that never ran
  });
  proc.on('exit', (code, sig) => onExit(c, proc, code, sig));
  c.proc = proc;
  c.held = false;
  c.policy.started();
  tellWatchdog('group', proc.pid);
}

/**
 * A child's output, line by line, each line prefixed with its name (unless it names itself already).
 * @param {string} name @param {import('node:stream').Readable | null} stream @param {import('./supervise/output.js').LineOutput} to
 */
function relay(name, stream, to) {
  if (!stream) return;
  let rest = ''; // a line split across chunks is relayed whole
  const put = (/** @type {string} */ line) => { if (line.trim()) to.line(line.startsWith(`[${name}]`) ? line : `[${name}] ${line}`); };
  stream.on('data', (d) => {
    const lines = (rest + d.toString()).split('\n');
    rest = lines.pop() ?? '';
    if (rest.length > 65536) { lines.push(rest); rest = ''; }
    lines.forEach(put);
  });
  stream.on('end', () => put(rest));
}

/**
 * A child's process ended. Ours to handle only if it is still the child's current process: a process we
 * stopped ourselves (a dependent of a dead master, a superseded one) has been detached from its child first.
 * @param {Child} c @param {import('node:child_process').ChildProcess} proc
 * @param {number | null} code @param {string | null} sig
 */
function onExit(c, proc, code, sig) {
  if (stopping || proc !== c.proc) return;
  c.proc = null;
  const why = sig || code;
  if (code === CONFIG_ERROR) {
    log(`${c.name} exited (${CONFIG_ERROR}): a configuration error (see above); not restarting it`);
    shutdown(CONFIG_ERROR);
    return;
  }
  const d = c.policy.crashed();
  const span = seconds(d.windowMs);
  if (d.giveUp) {
    log(`giving up: ${c.name} crashed ${d.crashes} times in ${span}; last exit ${why}; see the lines above`);
    shutdown(1);
    return;
  }
  const core = c.name === 'roscore';
  const deps = core ? [...children.values()].filter((x) => MASTER_DEPENDENTS.includes(x.name)) : [];
  log(`${c.name} exited (${why}); restarting ${restartDelay(d.delayMs)} (crash ${d.crashes} of ${d.maxCrashes} in ${span})`
    + (deps.length ? `; then ${deps.map((x) => x.name).join(' and ')}, which must register with the new master` : ''));
  restart(c, proc.pid, d.delayMs, deps).catch((e) => {
    if (!stopping) { log(`restarting ${c.name} failed: ${e.stack || e}`); shutdown(1); }
  });
}

/**
 * Clear what is left of the dead child, wait out the back-off, start it again. For roscore: stop its
 * dependents at once, and start them again once the new master answers.
 * @param {Child} c @param {number | undefined} oldPgid @param {number} delayMs @param {Child[]} deps
 */
async function restart(c, oldPgid, delayMs, deps) {
  const gen = ++c.gen;
  const core = c.name === 'roscore';
  if (core) coreDown = true;
  const stops = deps.map((d) => {
    d.gen++; // drop a restart of its own that may be pending
    d.held = true;
    const p = d.proc;
    d.proc = null; // its exit is ours, not a crash
    return clearChild(d.name, p?.pid, `${d.name} (its master died)`);
  });
  // (The dependents may take their time: only their own start waits for them to be gone.)
  const stopped = Promise.all(stops);
  stopped.catch(() => { /* awaited below, unless this restart is dropped first */ });
  await Promise.all([clearChild(c.name, oldPgid, c.name), pause(delayMs)]);
  if (stopping || gen !== c.gen) return;
  if (coreDown && !core && MASTER_DEPENDENTS.includes(c.name)) { c.held = true; return; } // roscore's restart starts it
  log(`starting ${c.name} again`);
  spawnChild(c);
  if (!core) return;
  const up = await waitUntilAsync(() => masterOnline(env.rosMasterUri), 20_000);
  if (stopping || gen !== c.gen) return;
  if (!up) {
    // Counts as a crash of roscore: its exit handler restarts it (and its dependents stay held).
    log('the new roscore does not answer within 20 s; killing it');
    signalGroup(c.proc?.pid, 'SIGKILL');
    return;
  }
  await stopped;
  if (stopping || gen !== c.gen) return;
  coreDown = false;
  const held = [...children.values()].filter((x) => x.held);
  log(`the ROS master answers again${held.length ? `; starting ${held.map((x) => x.name).join(' and ')} again` : ''}`);
  for (const x of held) spawnChild(x);
}

/** A back-off wait; ends early when the stack stops. @param {number} ms */
function pause(ms) {
  return new Promise((resolve) => {
    const done = () => { clearTimeout(t); wakers.delete(done); resolve(undefined); };
    const t = setTimeout(done, ms);
    wakers.add(done);
    if (stopping) done();
  });
}

/**
 * Stop whatever is left of one child: the members of its process group and the processes carrying its
 * marker (SIGTERM, SIGKILL after a grace), and wait until they are gone.
 * @param {string} name @param {number | undefined} pgid @param {string} what for the log
 */
async function clearChild(name, pgid, what) {
  const left = () => stackProcs().filter((p) => p.child === name || (pgid && p.pgrp === pgid)).map((p) => p.pid);
  let pids = left();
  if (pids.length) {
    signalGroup(pgid, 'SIGTERM');
    pids.forEach((p) => signal(p, 'SIGTERM'));
    await waitUntil(() => left().length === 0, CLEANUP_GRACE_MS);
    pids = left();
    if (pids.length) {
      log(`${what}: ${pids.map(procName).join(', ')} still running ${seconds(CLEANUP_GRACE_MS)} after SIGTERM; killing ${pids.length === 1 ? 'it' : 'them'}`);
      signalGroup(pgid, 'SIGKILL');
      pids.forEach((p) => signal(p, 'SIGKILL'));
      // Killed, a process is gone only once the kernel has ended all its threads: its successor (the next
      // roslaunch's node of the same name) must not start beside it, and if it does the log says so.
      await waitUntil(() => left().length === 0, KILL_WAIT_MS);
      pids = left();
      if (pids.length) log(`${what}: ${pids.map(procName).join(', ')} still there ${seconds(KILL_WAIT_MS)} after SIGKILL; going on`);
    }
  }
  if (pgid && !stackProcs().some((p) => p.pgrp === pgid)) tellWatchdog('forget', pgid);
}

/** A process as the log names it: its ROS node name, else its program. @param {number} pid */
function procName(pid) {
  try {
    const argv = fs.readFileSync(`/proc/${pid}/cmdline`, 'latin1').split('\0').filter(Boolean);
    const node = argv.find((a) => a.startsWith('__name:='));
    return node ? node.slice('__name:='.length) : path.basename(argv.slice(1).find((a) => a.startsWith('/')) ?? argv[0] ?? String(pid));
  } catch { return String(pid); }
}

async function waitFor(pred, timeoutMs, what) {
  if (!(await waitUntilAsync(pred, timeoutMs))) {
    if (stopping) throw new Error('stopping');
    throw new Error(`timed out waiting for ${what}`);
  }
}

/** Poll an async predicate every 100 ms; false on timeout; throws once the stack stops. */
async function waitUntilAsync(pred, timeoutMs) {
  const end = Date.now() + timeoutMs;
  while (Date.now() < end) {
    if (stopping) throw new Error('stopping');
    if (await pred()) return true;
    await new Promise((r) => setTimeout(r, 100));
  }
  return false;
}

const exited = (p) => p.exitCode !== null || p.signalCode !== null;
const alive = (pid) => { try { process.kill(pid, 0); return true; } catch { return false; } };
const signal = (pid, sig) => { try { process.kill(pid, sig); } catch { /* gone */ } };
const signalGroup = (pgid, sig) => { if (pgid) signal(-pgid, sig); };

/**
 * Live processes of this stack, found by the marker in their environment, with their process group and
 * the child they belong to (CELL_STACK_CHILD).
 * @returns {{pid: number, pgrp: number, child: string | null}[]}
 */
function stackProcs() {
  const out = [];
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d) || Number(d) === process.pid) continue;
    try {
      const environ = fs.readFileSync(`/proc/${d}/environ`, 'latin1');
      if (!environ.includes(`CELL_STACK_ID=${STACK_ID}`)) continue;
      const stat = fs.readFileSync(`/proc/${d}/stat`, 'latin1');
      const [state, , pgrp] = stat.slice(stat.lastIndexOf(')') + 2).split(' ');
      if (state === 'Z' || state === 'X') continue;
      const child = environ.split('\0').find((e) => e.startsWith('CELL_STACK_CHILD='))?.slice('CELL_STACK_CHILD='.length) ?? null;
      out.push({ pid: Number(d), pgrp: Number(pgrp), child });
    } catch { /* gone or not ours */ }
  }
  return out;
}

/** Processes of this stack still running, found by the marker in their environment. */
const markedPids = () => stackProcs().map((p) => p.pid);

async function shutdown(code = 0) {
  if (stopping) return;
  stopping = true;
  for (const w of [...wakers]) w(); // a restart waiting out its back-off is dropped
  log('stopping...');
  // Within 5 s: the signals until 3.8 s, then SIGKILL for what is left and time for it (and the watchdog's check)
  // to finish: on a busy host a killed process takes a while to be reaped.
  const t0 = Date.now();
  // Front first (BFF, launch, sim), then the master, so nodes can unregister cleanly.
  const procs = (names) => [...children.values()].filter((c) => names(c.name) && c.proc).map((c) => /** @type {any} */ (c.proc));
  const front = procs((n) => n !== 'roscore');
  front.forEach((p) => signalGroup(p.pid, 'SIGINT'));
  await waitUntil(() => front.every(exited), 2800);
  const core = procs((n) => n === 'roscore');
  if (core.length) {
    core.forEach((p) => signalGroup(p.pid, 'SIGTERM'));
    await waitUntil(() => core.every(exited), Math.max(200, t0 + 3800 - Date.now()));
  }
  // Whatever is left: leftovers of a child that was being restarted, nodes that ignored the signal...
  for (const pid of markedPids()) signal(pid, 'SIGKILL');
  await waitUntil(() => markedPids().every((p) => !alive(p)), 700);
  await stopWatchdog(Math.max(400, t0 + 4800 - Date.now()));
  log('stopped');
  await Promise.all([out.flush(150), err.flush(150)]); // a reader that does not read loses the last lines, not the exit
  process.exit(code);
}

async function waitUntil(pred, ms) {
  const end = Date.now() + ms;
  while (Date.now() < end && !pred()) await new Promise((r) => setTimeout(r, 50));
}

process.on('SIGINT', () => shutdown(0));
process.on('SIGTERM', () => shutdown(0));
process.on('SIGHUP', () => shutdown(0));
// Whatever goes wrong in the supervisor itself, the children must not outlive it.
process.on('uncaughtException', (e) => { err.line(`[stack] ${e.stack || e}`); shutdown(1); });
const parent = process.ppid;
setInterval(() => { if (process.ppid !== parent) shutdown(1); }, 500).unref();
// The supervisor allocates little (child output lines, a health probe every few seconds), so V8 seldom runs a major
// GC: what outlives two scavenges piles up in the old space until the next one (--trace-gc in the soak: 13 -> 19 MB
// in 5 minutes, no Mark-Compact), and the RSS climbed 0.5 MiB/min for half an hour. A full GC once a minute (a few
// ms on a heap this small) keeps it flat.
v8.setFlagsFromString('--expose-gc');
const fullGc = /** @type {() => void} */ (vm.runInNewContext('gc'));
setInterval(fullGc, 60_000).unref();

async function main() {
  let cell;
  /** @type {{host: string, groups: string[]}[]} */
  let arms;
  /** @type {number | null} */
  let livenessGraceMs;
  try {
    livenessGraceMs = graceFromEnv(process.env);
  } catch (e) { await exitWith(2, /** @type {Error} */ (e).message); }
  try {
    cell = loadCell(env.cellConfig, FEATURES);
    arms = armsOf(resolveHosts(cell.manual, process.env));
  } catch (e) {
    if (e instanceof CellConfigError) await exitWith(2, e.message);
    if (e instanceof Error && /^(UR_HOSTS?|manual\.groups)/.test(e.message)) await exitWith(2, `${env.cellConfig}: ${e.message}`);
    throw e;
  }
  // One UR controller per arm (each at its own address); a cell without motion groups has the one at UR_HOST.
  const where = arms.length ? arms.map((a) => `${a.host} (${a.groups.join(', ')})`).join(' and ') : urHost;
  if (await masterOnline(env.rosMasterUri)) {
    log(`using the ROS master at ${env.rosMasterUri} (not started here, so not restarted here either)`);
  } else {
    log(`starting roscore on port ${masterPort}`);
    startRos('roscore', `roscore -p ${masterPort}`);
    // (A roscore that dies meanwhile is restarted; its dependents are not started yet, so none are held.)
    await waitFor(async () => !coreDown && (await masterOnline(env.rosMasterUri)), 60_000, 'roscore');
  }
  const simulated = cell.robot?.simulated !== false && process.env.UR_SIM !== '0';
  const rosControlSim = cell.simulation?.kind === 'ros_control';
  if (simulated && rosControlSim) {
    // The sim stands for the arm's own ROS driver (ros_control): it speaks ROS only, no controller address.
    log('starting the simulated cell: the arm\'s ros_control driver');
    const extra = (process.env.SIM_ARGS || '').split(/\s+/).filter(Boolean).map(shellQuote).join(' ');
    startRos('sim', `python -m sim ${extra}`);
  } else if (simulated && fs.existsSync(path.join(REPO_ROOT, 'sim/__main__.py'))) {
    log(`starting the simulated cell: ${arms.length > 1 ? 'UR controllers' : 'the UR controller'} at ${where}`);
    // SIM_ARGS: extra `python -m sim` options, e.g. "--no-cameras" or "--camera-size 320x240".
    const extra = (process.env.SIM_ARGS || '').split(/\s+/).filter(Boolean).map(shellQuote).join(' ');
    // One sim process, one physics world for every arm (a hand-over needs both arms in one world), one controller
    // emulator per arm on that arm's address.
    const hosts = arms.length > 1
      ? `--hosts ${shellQuote(arms.map((a) => `${a.groups[0]}=${a.host}`).join(','))}`
      : `--host ${shellQuote(arms[0]?.host ?? urHost)}`;
    startRos('sim', `python -m sim ${hosts} ${extra}`);
  } else {
    log(`robot: ${arms.length > 1 ? 'UR controllers' : 'UR controller'} at ${where}`);
  }
  const launches = launchFiles(cell, path.join(REPO_ROOT, 'ros_backend/src/cell_bringup')).map(shellQuote).join(' ');
  startRos('ros', `roslaunch --wait ${launches} cell_config:=${shellQuote(env.cellConfig)} rosbridge_port:=${env.rosbridgePort}`);
  await startLocalBroker(cell);
  const lan = Object.values(os.networkInterfaces()).flat().find((i) => i && i.family === 'IPv4' && !i.internal);
  // The address the plant page links this cell with (its birth's Properties/URL), unless the cell file or the
  // environment names one.
  if (cell.plant && !cell.plant.url && !childEnv.PLANT_CELL_URL) {
    childEnv.PLANT_CELL_URL = lan ? `https://${lan.address}:${env.tlsPort}/` : `http://localhost:${env.port}/`;
  }
  const bff = start('bff', process.execPath, [path.join(REPO_ROOT, 'bff/src/server.js')]);
  if (livenessGraceMs) watchLiveness(bff, async (ms) => !!(await bffHealth(ms)), livenessGraceMs);
  // Long enough for a few restarts of a child that dies while starting (a crash loop ends the stack first).
  await waitFor(async () => !!(await bffHealth()), 60_000, 'the BFF');
  try {
    await waitFor(async () => (await bffHealth())?.ros?.rosbridge === true, 30000, 'rosbridge');
  } catch (e) {
    if (stopping) throw e;
    log('warning: rosbridge does not answer yet; the app will connect when it does');
  }
  log(`ready: http://localhost:${env.port}/`);
  if (lan) log(`phones and tablets: https://${lan.address}:${env.tlsPort}/ (trust the cell's certificate first: http://${lan.address}:${env.port}/trust)`);
}

/**
 * The plant's MQTT broker for a demo or a test: when the cell file's (or PLANT_BROKER_URL's) broker is mqtt:// on
 * this machine and nothing answers there, run Debian's mosquitto on that port (anonymous, loopback only). A plant
 * runs its own broker; then this does nothing.
 * @param {any} cell
 */
async function startLocalBroker(cell) {
  if (!cell.plant) return;
  let url;
  try { url = new URL(process.env.PLANT_BROKER_URL || cell.plant.broker); } catch { return; }
  if (url.protocol !== 'mqtt:' || !['127.0.0.1', 'localhost'].includes(url.hostname)) return;
  const port = Number(url.port || 1883);
  if (await tcpReachable('127.0.0.1', port)) return;
  const conf = path.join(env.dataDir, 'mosquitto.conf');
  fs.writeFileSync(conf, `listener ${port} 127.0.0.1\nallow_anonymous true\npersistence false\n`);
  log(`starting a local MQTT broker for the plant view (mosquitto on port ${port})`);
  start('broker', '/usr/sbin/mosquitto', ['-c', conf]);
  await waitFor(() => tcpReachable('127.0.0.1', port), 10_000, 'mosquitto');
}

/** The BFF's health answer, or null when it does not answer within `timeoutMs`. @returns {Promise<any>} */
async function bffHealth(timeoutMs = 2000) {
  try {
    const r = await fetch(`http://127.0.0.1:${env.port}/api/health`, { signal: AbortSignal.timeout(timeoutMs) });
    return r.ok ? await r.json() : null;
  } catch { return null; }
}

/**
 * Probe a running child; kill it when it has answered since it started and then not for `graceMs`: its exit
 * handler restarts it (and counts the crash).
 * @param {Child} c @param {(timeoutMs: number) => Promise<boolean>} probe @param {number} graceMs
 */
function watchLiveness(c, probe, graceMs) {
  const liveness = new Liveness({ graceMs });
  /** @type {import('node:child_process').ChildProcess | null} */
  let judged = null;
  let probing = false;
  const timer = setInterval(async () => {
    const p = c.proc;
    if (stopping || probing || !p || exited(p)) return;
    if (p !== judged) { judged = p; liveness.started(); }
    probing = true;
    try {
      const ok = await probe(Math.min(5000, graceMs));
      if (p !== c.proc || stopping) return;
      if (ok) liveness.answered();
      else if (liveness.hung()) {
        log(`${c.name} has not answered its health check for ${seconds(liveness.silentMs())}; killing it to restart it`);
        signalGroup(p.pid, 'SIGKILL');
      }
    } finally { probing = false; }
  }, Math.max(250, Math.min(5000, graceMs / 4)));
  timer.unref();
}

/** @param {string} s */
function shellQuote(s) {
  return `'${String(s).replace(/'/g, `'\\''`)}'`;
}

/** Before any child runs: say why on stderr and exit. @param {number} code @param {string} message */
async function exitWith(code, message) {
  err.line(message);
  await err.flush(2000);
  process.exit(code);
}

main().catch((e) => {
  if (!stopping) { err.line(`[stack] ${e.message}`); shutdown(1); }
});
