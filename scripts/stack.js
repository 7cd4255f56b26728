#!/usr/bin/env node
// `npm start`: roscore (unless ROS_MASTER_URI answers), the simulated cell, the ROS side and the BFF.
// Every child runs in its own process group and carries a stack marker in its environment, so Ctrl-C
// stops all of them (roslaunch's nodes live in their own sessions) within 5 s and leaves nothing behind.
// A watchdog (scripts/watchdog.js, detached) stops them too if this supervisor dies, even by SIGKILL.
import { spawn } from 'node:child_process';
import crypto from 'node:crypto';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { readEnv, REPO_ROOT } from '../bff/src/core/config/env.js';
import { loadCell, CellConfigError } from '../bff/src/core/config/cell.js';
import { FEATURES } from '../bff/src/features/index.js';
import { launchFiles } from './feature-launch.js';
import { masterOnline } from '../bff/src/core/ros/health.js';

const env = readEnv();
const urHost = process.env.UR_HOST || '127.0.0.1'; // the UR controller, or where the simulated one listens
const STACK_ID = crypto.randomUUID();
const rosHome = path.join(env.dataDir, 'ros');
fs.mkdirSync(rosHome, { recursive: true });
const masterPort = Number(new URL(env.rosMasterUri).port || 11311);
const log = (m) => console.log(`[stack] ${m}`);

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

/** @type {{name: string, proc: import('node:child_process').ChildProcess, essential: boolean}[]} */
const children = [];
let stopping = false;

// The watchdog runs in its own session and holds the read end of a pipe whose write end only this process
// has: when the supervisor dies, however it dies, the watchdog sees EOF and stops every process of the stack
// (child groups and marked processes). It starts before the first child and learns each child's group as it
// starts; a child spawned at the moment of a SIGKILL is still found by its marker. After a clean shutdown,
// `done` + EOF make it check that nothing is left and exit.
const WATCHDOG = fileURLToPath(new URL('./watchdog.js', import.meta.url));
/** @type {import('node:child_process').ChildProcess | null} */
let watchdog = null;
let watchdogRestarts = 0;

function startWatchdog() {
  const groups = children.filter((c) => c.proc.pid && !exited(c.proc)).map((c) => String(c.proc.pid));
  const wd = spawn(process.execPath, [WATCHDOG, STACK_ID, String(process.pid), ...groups],
    { detached: true, stdio: ['pipe', 'ignore', 'inherit'] });
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

/** Tell the watchdog about a new child group. */
function watch(pid) {
  if (pid && watchdog?.stdin?.writable) watchdog.stdin.write(`group ${pid}\n`);
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
function startRos(name, command, essential = true) {
  return start(name, 'bash', ['-c', `source scripts/ros-env.sh && exec ${command}`], essential);
}

function start(name, cmd, args, essential = true) {
  if (!watchdog) watchdog = startWatchdog();
  const proc = spawn(cmd, args, { cwd: REPO_ROOT, env: childEnv, detached: true, stdio: ['ignore', 'pipe', 'pipe'] });
  const prefix = (stream, out) => stream.on('data', (d) => {
    for (const line of d.toString().split('\n')) {
      if (line.trim()) out.write(line.startsWith(`[${name}]`) ? `${line}\n` : `[${name}] ${line}\n`);
    }
  });
  prefix(proc.stdout, process.stdout);
  prefix(proc.stderr, process.stderr);
  proc.on('exit', (code, sig) => {
    if (stopping) return;
    log(`${name} exited (${sig || code})`);
    if (essential) shutdown(1);
  });
  children.push({ name, proc, essential });
  watch(proc.pid);
  return proc;
}

async function waitFor(pred, timeoutMs, what) {
  const end = Date.now() + timeoutMs;
  while (Date.now() < end) {
    if (stopping) throw new Error('stopping');
    if (await pred()) return;
    await new Promise((r) => setTimeout(r, 100));
  }
  throw new Error(`timed out waiting for ${what}`);
}

const exited = (p) => p.exitCode !== null || p.signalCode !== null;
const alive = (pid) => { try { process.kill(pid, 0); return true; } catch { return false; } };

/** Processes of this stack still running, found by the marker in their environment. */
function markedPids() {
  const pids = [];
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d) || Number(d) === process.pid) continue;
    try {
      if (fs.readFileSync(`/proc/${d}/environ`).includes(`CELL_STACK_ID=${STACK_ID}`)) pids.push(Number(d));
    } catch { /* gone or not ours */ }
  }
  return pids;
}

async function shutdown(code = 0) {
  if (stopping) return;
  stopping = true;
  log('stopping...');
  const deadline = Date.now() + 4500;
  const signalGroup = (p, sig) => { try { process.kill(-p.pid, sig); } catch { /* already gone */ } };
  // Front first (BFF, launch, sim), then the master, so nodes can unregister cleanly.
  const front = children.filter((c) => c.name !== 'roscore');
  front.forEach((c) => signalGroup(c.proc, 'SIGINT'));
  await waitUntil(() => front.every((c) => exited(c.proc)), Math.min(3000, deadline - Date.now()));
  const core = children.find((c) => c.name === 'roscore');
  if (core) {
    signalGroup(core.proc, 'SIGTERM');
    await waitUntil(() => exited(core.proc), Math.max(200, deadline - Date.now() - 500));
  }
  for (const pid of markedPids()) try { process.kill(pid, 'SIGKILL'); } catch { /* gone */ }
  await waitUntil(() => markedPids().every((p) => !alive(p)), 400);
  await stopWatchdog(Math.max(300, deadline - Date.now()));
  log('stopped');
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
process.on('uncaughtException', (e) => { console.error(`[stack] ${e.stack || e}`); shutdown(1); });
process.stdout.on('error', () => shutdown(1));
const parent = process.ppid;
setInterval(() => { if (process.ppid !== parent) shutdown(1); }, 500).unref();

async function main() {
  let cell;
  try {
    cell = loadCell(env.cellConfig, FEATURES);
  } catch (e) {
    if (e instanceof CellConfigError) { console.error(e.message); process.exit(2); }
    throw e;
  }
  if (await masterOnline(env.rosMasterUri)) {
    log(`using the ROS master at ${env.rosMasterUri}`);
  } else {
    log(`starting roscore on port ${masterPort}`);
    startRos('roscore', `roscore -p ${masterPort}`);
    await waitFor(() => masterOnline(env.rosMasterUri), 20000, 'roscore');
  }
  const simulated = cell.robot?.simulated !== false && process.env.UR_SIM !== '0';
  if (simulated && fs.existsSync(path.join(REPO_ROOT, 'sim/__main__.py'))) {
    log(`starting the simulated UR5 cell at ${urHost}`);
    // SIM_ARGS: extra `python -m sim` options, e.g. "--no-cameras" or "--camera-size 320x240".
    const extra = (process.env.SIM_ARGS || '').split(/\s+/).filter(Boolean).map(shellQuote).join(' ');
    startRos('sim', `python -m sim --host ${shellQuote(urHost)} ${extra}`, false);
  } else {
    log(`robot: UR controller at ${urHost}`);
  }
  const launches = launchFiles(cell, path.join(REPO_ROOT, 'ros_backend/src/cell_bringup')).map(shellQuote).join(' ');
  startRos('ros', `roslaunch --wait ${launches} cell_config:=${shellQuote(env.cellConfig)} rosbridge_port:=${env.rosbridgePort}`);
  start('bff', process.execPath, [path.join(REPO_ROOT, 'bff/src/server.js')]);
  /** @returns {Promise<any>} */
  const health = async () => {
    try { const r = await fetch(`http://127.0.0.1:${env.port}/api/health`); return r.ok ? await r.json() : null; } catch { return null; }
  };
  await waitFor(async () => !!(await health()), 30000, 'the BFF');
  try {
    await waitFor(async () => (await health())?.ros?.rosbridge === true, 30000, 'rosbridge');
  } catch (e) {
    if (stopping) throw e;
    log('warning: rosbridge does not answer yet; the app will connect when it does');
  }
  const lan = Object.values(os.networkInterfaces()).flat().find((i) => i && i.family === 'IPv4' && !i.internal);
  log(`ready: http://localhost:${env.port}/`);
  if (lan) log(`phones and tablets: https://${lan.address}:${env.tlsPort}/ (trust the cell's certificate first: http://${lan.address}:${env.port}/trust)`);
}

/** @param {string} s */
function shellQuote(s) {
  return `'${String(s).replace(/'/g, `'\\''`)}'`;
}

main().catch((e) => {
  if (!stopping) { console.error(`[stack] ${e.message}`); shutdown(1); }
});
