// Supervision (scripts/stack.js): a child of the stack that dies is restarted with a back-off and the stack
// recovers by itself; a crash loop ends the stack with a clear message and exit code 1; Ctrl-C during a
// back-off wait still stops everything within 5 s. Real processes are SIGKILLed and the recovery is timed.
import { describe, test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import net from 'node:net';
import { WebSocket } from 'ws';
import { stackEnv, addUser, startStack, stopStack, pidsOfStack } from '../../e2e/lib/stack.js';

// Ports 28780-28786 and 28880-28886; the simulated cell at 127.0.0.31.
const BASE = 28780;
const LOOP_BASE = 28880;
const UR_HOST = '127.0.0.31';
const HANG_S = 6;

/** Poll `pred` every 50 ms until it holds or `ms` have passed; true if it held. */
async function until(pred, ms) {
  const end = Date.now() + ms;
  for (;;) {
    if (await pred()) return true;
    if (Date.now() >= end) return false;
    await new Promise((r) => setTimeout(r, 50));
  }
}

const portFree = (port) => new Promise((resolve) => {
  const s = net.createServer().once('error', () => resolve(false)).listen(port, '127.0.0.1', () => s.close(() => resolve(true)));
});
const read = (pid, what) => { try { return fs.readFileSync(`/proc/${pid}/${what}`, 'utf8'); } catch { return ''; } };
const read0 = (file) => { try { return fs.readFileSync(file, 'utf8'); } catch { return ''; } };
const cmdline = (pid) => read(pid, 'cmdline').replace(/\0/g, ' ').trim();
const ppid = (pid) => Number(read(pid, 'stat').split(') ')[1]?.split(' ')[1]);
const describePids = (pids) => pids.map((p) => `${p}: ${cmdline(p)}`);

/** The supervisor's child whose command line matches `re` (roscore, roslaunch, the BFF, the sim). */
function childPid(env, supervisor, re) {
  return pidsOfStack(env.DATA_DIR).find((p) => ppid(p) === supervisor && re.test(cmdline(p))) ?? null;
}

/** Live pids carrying `entry` (e.g. `CELL_STACK_ID=...`) in their environment. */
function pidsWithEnv(entry) {
  return fs.readdirSync('/proc').filter((d) => /^\d+$/.test(d) && Number(d) !== process.pid)
    .filter((d) => read(d, 'environ').split('\0').includes(entry) && !/\) Z /.test(read(d, 'stat'))).map(Number);
}

function markerOf(env) {
  for (const pid of pidsOfStack(env.DATA_DIR)) {
    const entry = read(pid, 'environ').split('\0').find((e) => e.startsWith('CELL_STACK_ID='));
    if (entry) return entry;
  }
  return null;
}

/** Every ROS node process of the stack runs once: `__name:=x` never appears twice. */
function duplicateNodes(env) {
  const names = pidsOfStack(env.DATA_DIR).map((p) => cmdline(p).match(/__name:=(\S+)/)?.[1]).filter(Boolean);
  return names.filter((n, i) => names.indexOf(n) !== i);
}

/**
 * Each process of a node that runs twice, for the failure message: pid, parent, state, whether it ran before the
 * kill (`before`: the node pids then).
 * @param {Record<string, string>} env @param {number[]} before
 */
function describeDuplicates(env, before) {
  const dup = new Set(duplicateNodes(env));
  return pidsOfStack(env.DATA_DIR).filter((p) => dup.has(cmdline(p).match(/__name:=(\S+)/)?.[1] ?? ''))
    .map((p) => `${p}${before.includes(p) ? ' (ran before the kill)' : ''}, parent ${ppid(p)} (${cmdline(ppid(p)).slice(0, 80)}), `
      + `state ${read(p, 'stat').split(') ')[1]?.split(' ')[0]}: ${cmdline(p).slice(0, 200)}`).join('\n');
}
const nodePids = (env) => pidsOfStack(env.DATA_DIR).filter((p) => /__name:=/.test(cmdline(p)));

async function health(port) {
  try {
    const r = await fetch(`http://127.0.0.1:${port}/api/health`, { signal: AbortSignal.timeout(1000) });
    return r.ok ? await r.json() : null;
  } catch { return null; }
}

/**
 * One rosbridge service call on a fresh socket (rosbridge itself, or the BFF's /ros with a session cookie);
 * resolves with the response values, or null on any failure.
 */
function callService(url, service, { cookie, timeoutMs = 3000 } = {}) {
  return new Promise((resolve) => {
    const ws = new WebSocket(url, cookie ? { headers: { cookie } } : {});
    const done = (v) => { clearTimeout(timer); ws.removeAllListeners(); ws.on('error', () => {}); ws.terminate(); resolve(v); };
    const timer = setTimeout(() => done(null), timeoutMs);
    ws.once('error', () => done(null));
    ws.once('close', () => done(null));
    ws.once('open', () => ws.send(JSON.stringify({ op: 'call_service', id: 'probe', service, args: {} })));
    ws.on('message', (d) => {
      const m = JSON.parse(d.toString());
      if (m.op === 'service_response' && m.id === 'probe') done(m.result ? m.values : null);
    });
  });
}

/** XML-RPC lookupNode on the master: the node's URI, or null. */
async function lookupNode(masterUri, node) {
  try {
    const body = `<?xml version="1.0"?><methodCall><methodName>lookupNode</methodName><params><param><value><string>/test</string></value></param><param><value><string>${node}</string></value></param></params></methodCall>`;
    const r = await fetch(masterUri, { method: 'POST', headers: { 'content-type': 'text/xml' }, body, signal: AbortSignal.timeout(1000) });
    return (await r.text()).match(/<string>(https?:\/\/[^<]+)<\/string>/)?.[1] ?? null;
  } catch { return null; }
}

async function login(port, user, password) {
  const r = await fetch(`http://127.0.0.1:${port}/api/auth/login`, {
    method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ username: user, password }),
  });
  assert.equal(r.status, 200);
  return /** @type {string} */ (r.headers.get('set-cookie')).split(';')[0];
}

/** The stack's log since `from` (an offset into its output). */
const logSince = (stack, from) => stack.output().slice(from);

/** Whatever a failed run left behind must not outlive the test. */
function killLeftovers(env, marker) {
  for (const pid of [...pidsOfStack(env.DATA_DIR), ...(marker ? pidsWithEnv(marker) : [])]) {
    try { process.kill(pid, 'SIGKILL'); } catch { /* gone */ }
  }
}

describe('a running stack restarts what dies', { timeout: 300_000 }, () => {
  // The simulated cell runs here (no cameras, to spare the CPU) so roscore's case restarts it too.
  // A BFF that does not answer its health check for 6 s after it first answered is hung (30 s by default).
  const env = stackEnv({ port: BASE, masterPort: BASE + 1, rosbridgePort: BASE + 2, urHost: UR_HOST,
    extraEnv: { SIM_ARGS: '--no-cameras', LIVENESS_TIMEOUT_S: String(HANG_S) } });
  delete env.UR_SIM;
  const bff = `http://127.0.0.1:${BASE}`;
  const rosbridge = `ws://127.0.0.1:${BASE + 2}`;
  /** @type {Awaited<ReturnType<typeof startStack>>} */
  let stack;
  let marker = null;
  let cookie = '';
  /** @type {Record<string, number>} */
  const took = {};

  before(async () => {
    addUser(env, 'admin', 'admin', 'admin-password');
    stack = await startStack(env, 120_000);
    marker = markerOf(env);
    cookie = await login(BASE, 'admin', 'admin-password');
  });
  after(async () => {
    if (stack) await stopStack(stack.proc);
    killLeftovers(env, marker);
  });

  test('kill -9 of the BFF: /api/health answers again, the login still holds, the log says why', async (t) => {
    const old = childPid(env, stack.proc.pid, /bff\/src\/server\.js/);
    assert.ok(old, 'the BFF runs');
    const from = stack.output().length;
    const t0 = Date.now();
    process.kill(old, 'SIGKILL');
    assert.ok(await until(async () => (await health(BASE)) === null, 5000), 'the BFF is down');
    assert.ok(await until(async () => !!(await health(BASE)), 30_000), `the BFF is back:\n${logSince(stack, from)}`);
    took.bff = (Date.now() - t0) / 1000;
    t.diagnostic(`BFF: /api/health answers again ${took.bff} s after the SIGKILL`);
    assert.match(logSince(stack, from), /\[stack\] bff exited \(SIGKILL\); restarting at once \(crash 1 of 5 in 60 s\)/);
    const fresh = childPid(env, stack.proc.pid, /bff\/src\/server\.js/);
    assert.ok(fresh && fresh !== old);
    // The session key lives in DATA_DIR: the cookie from before the crash is still a login.
    const me = await fetch(`${bff}/api/auth/me`, { headers: { cookie } });
    assert.equal(me.status, 200);
    assert.equal((await me.json()).username, 'admin');
  });

  test('kill -9 of roslaunch: its orphaned nodes are cleared, rosbridge and the cell nodes come back once each', async (t) => {
    const old = childPid(env, stack.proc.pid, /roslaunch --wait/);
    assert.ok(old, 'roslaunch runs');
    assert.ok(await callService(rosbridge, '/cell/get_mode'), 'a service works through rosbridge before');
    const oldNodes = pidsOfStack(env.DATA_DIR).filter((p) => /__name:=/.test(cmdline(p)) && ppid(p) === old);
    assert.ok(oldNodes.length >= 3, `roslaunch's nodes: ${describePids(oldNodes)}`);
    const from = stack.output().length;
    const t0 = Date.now();
    process.kill(old, 'SIGKILL');
    const back = await until(async () => ![null, old].includes(childPid(env, stack.proc.pid, /roslaunch --wait/))
      && !!(await callService(rosbridge, '/cell/get_mode', { timeoutMs: 1000 })), 60_000);
    assert.ok(back, `rosbridge and /cell/get_mode are back:\n${logSince(stack, from)}`);
    took.ros = (Date.now() - t0) / 1000;
    t.diagnostic(`roslaunch: /cell/get_mode answers through rosbridge again ${took.ros} s after the SIGKILL`);
    assert.match(logSince(stack, from), /\[stack\] ros exited \(SIGKILL\); restarting at once \(crash 1 of 5 in 60 s\)/);
    assert.deepEqual(describePids(oldNodes.filter((p) => read(p, 'stat') && !/\) Z /.test(read(p, 'stat')))), [], 'the old nodes are gone');
    assert.deepEqual(duplicateNodes(env), [], `no node runs twice:\n${describeDuplicates(env, oldNodes)}\n${logSince(stack, from)}`);
    // The BFF's /ros reaches the new rosbridge too.
    assert.ok(await until(() => callService(`ws://127.0.0.1:${BASE}/ros`, '/cell/get_mode', { cookie }), 10_000));
  });

  test('kill -9 of roscore: a new master, then the ROS side and the simulated cell registered with it', async (t) => {
    const old = childPid(env, stack.proc.pid, /roscore -p/);
    const oldSim = childPid(env, stack.proc.pid, /-m sim/);
    const oldLaunch = childPid(env, stack.proc.pid, /roslaunch --wait/);
    assert.ok(old && oldSim && oldLaunch, 'roscore, the sim and roslaunch run');
    const oldSimUri = await lookupNode(env.ROS_MASTER_URI, '/sim_cell');
    assert.ok(oldSimUri, 'the sim is registered');
    const oldNodes = nodePids(env);
    const from = stack.output().length;
    const t0 = Date.now();
    process.kill(old, 'SIGKILL');
    // End to end: the browser's path (BFF /ros -> rosbridge -> node), and the sim's node on the new master.
    const back = await until(async () => ![null, old].includes(childPid(env, stack.proc.pid, /roscore -p/))
      && ![null, oldLaunch].includes(childPid(env, stack.proc.pid, /roslaunch --wait/))
      && !!(await callService(`ws://127.0.0.1:${BASE}/ros`, '/cell/get_mode', { cookie, timeoutMs: 1000 })), 90_000);
    assert.ok(back, `/cell/get_mode through the BFF is back:\n${logSince(stack, from)}`);
    took.roscore = (Date.now() - t0) / 1000;
    const simBack = await until(async () => {
      const uri = await lookupNode(env.ROS_MASTER_URI, '/sim_cell');
      return !!uri && uri !== oldSimUri;
    }, 30_000);
    took.roscoreSim = (Date.now() - t0) / 1000;
    t.diagnostic(`roscore: /cell/get_mode through the BFF again ${took.roscore} s after the SIGKILL; the sim registered again at ${took.roscoreSim} s`);
    assert.ok(simBack, 'the restarted sim registered with the new master');
    const log = logSince(stack, from);
    assert.match(log, /\[stack\] roscore exited \(SIGKILL\); restarting at once \(crash 1 of 5 in 60 s\); then sim and ros, which must register with the new master/);
    assert.match(log, /\[stack\] the ROS master answers again; starting sim and ros again/);
    assert.doesNotMatch(log, /\[stack\] (ros|sim) exited/, 'stopping the dependents is not a crash of theirs');
    assert.notEqual(childPid(env, stack.proc.pid, /-m sim/), oldSim);
    assert.notEqual(childPid(env, stack.proc.pid, /roslaunch --wait/), oldLaunch);
    assert.equal(pidsOfStack(env.DATA_DIR).filter((p) => /rosmaster --core/.test(cmdline(p))).length, 1, 'one master');
    assert.deepEqual(duplicateNodes(env), [], `no node runs twice:\n${describeDuplicates(env, oldNodes)}\n${log}`);
  });

  test('kill -9 of the simulated cell: it comes back at UR_HOST, registers again, and the robot driver reconnects', async (t) => {
    const old = childPid(env, stack.proc.pid, /-m sim/);
    const oldUri = await lookupNode(env.ROS_MASTER_URI, '/sim_cell');
    assert.ok(old && oldUri);
    // The robot driver's view (cell_msgs/RobotState, ~20 Hz): it must lose the controller, then find the new one.
    /** @type {boolean[]} */
    const driverConnected = [];
    const watch = new WebSocket(rosbridge);
    t.after(() => watch.terminate());
    await new Promise((resolve, reject) => { watch.once('open', resolve); watch.once('error', reject); });
    watch.on('message', (d) => {
      const m = JSON.parse(d.toString());
      if (m.op === 'publish' && m.topic === '/cell/manual/arm/state') driverConnected.push(m.msg.connected);
    });
    watch.send(JSON.stringify({ op: 'subscribe', id: 'driver', topic: '/cell/manual/arm/state', type: 'cell_msgs/RobotState', throttle_rate: 100 }));
    assert.ok(await until(() => driverConnected.at(-1) === true, 20_000), 'the driver is connected to the sim');
    const seen = driverConnected.length;
    const from = stack.output().length;
    const t0 = Date.now();
    process.kill(old, 'SIGKILL');
    const dashboard = () => new Promise((resolve) => {
      const s = net.connect({ host: UR_HOST, port: 29999 });
      const done = (v) => { s.destroy(); resolve(v); };
      s.setTimeout(1000, () => done(false));
      s.once('data', (d) => done(/Universal Robots Dashboard Server/.test(d.toString())));
      s.once('error', () => done(false));
    });
    const back = await until(async () => ![null, old].includes(childPid(env, stack.proc.pid, /-m sim/)) && (await dashboard())
      && ((await lookupNode(env.ROS_MASTER_URI, '/sim_cell')) ?? oldUri) !== oldUri, 60_000);
    assert.ok(back, `the sim is back:\n${logSince(stack, from)}`);
    took.sim = (Date.now() - t0) / 1000;
    t.diagnostic(`sim: the dashboard answers and /sim_cell is registered again ${took.sim} s after the SIGKILL`);
    const reconnected = await until(() => {
      const after = driverConnected.slice(seen);
      const lost = after.indexOf(false);
      return lost >= 0 && after.slice(lost).includes(true);
    }, 30_000);
    assert.ok(reconnected, `the driver lost the controller and found the new one: ${JSON.stringify(driverConnected.slice(seen, seen + 20))}`);
    took.simDriver = (Date.now() - t0) / 1000;
    t.diagnostic(`sim: the robot driver is connected to the new sim ${took.simDriver} s after the SIGKILL`);
    assert.match(logSince(stack, from), /\[stack\] sim exited \(SIGKILL\); restarting at once \(crash 1 of 5 in 60 s\)/);
  });

  test('a BFF that runs but no longer answers (SIGSTOP) is killed after LIVENESS_TIMEOUT_S and restarted', async (t) => {
    const old = childPid(env, stack.proc.pid, /bff\/src\/server\.js/);
    assert.ok(old && (await health(BASE)), 'the BFF runs and answers');
    const from = stack.output().length;
    const t0 = Date.now();
    process.kill(old, 'SIGSTOP'); // alive, its port open, its event loop answering nothing: a hang
    t.after(() => { try { process.kill(old, 'SIGKILL'); } catch { /* gone, as it should be */ } });
    assert.ok(await until(async () => (await health(BASE)) === null, 5000), 'the stopped BFF does not answer');
    assert.ok(await until(async () => !!(await health(BASE)), 60_000), `the BFF is back:\n${logSince(stack, from)}`);
    took.bffHung = (Date.now() - t0) / 1000;
    t.diagnostic(`hung BFF: /api/health answers again ${took.bffHung} s after its SIGSTOP (grace ${HANG_S} s)`);
    assert.ok(took.bffHung >= HANG_S, 'not killed before the grace period');
    const log = logSince(stack, from);
    assert.match(log, /\[stack\] bff has not answered its health check for [\d.]+ s; killing it to restart it/);
    assert.match(log, /\[stack\] bff exited \(SIGKILL\); restarting (?:at once|in [\d.]+ s) \(crash \d of 5 in 60 s\)/);
    assert.ok(!fs.existsSync(`/proc/${old}`) || /\) Z /.test(read(old, 'stat')), 'the hung process is gone');
    const fresh = childPid(env, stack.proc.pid, /bff\/src\/server\.js/);
    assert.ok(fresh && fresh !== old);
    assert.equal((await fetch(`${bff}/api/auth/me`, { headers: { cookie } })).status, 200, 'still signed in');
  });

  test('Ctrl-C while a restart waits out its back-off: no restart, everything gone within 5 s', async (t) => {
    const old = childPid(env, stack.proc.pid, /bff\/src\/server\.js/);
    assert.ok(old);
    const from = stack.output().length;
    const exited = new Promise((r) => stack.proc.once('exit', (code) => r(code)));
    // SIGINT the moment the supervisor announces the restart (it then waits at least 0.5 s).
    const announced = /\[stack\] bff exited \(SIGKILL\); restarting (?:at once|in [\d.]+ s) \(crash \d of 5 in 60 s\)/;
    const waiting = new Promise((resolve) => {
      const onData = () => {
        if (!announced.test(logSince(stack, from))) return;
        stack.proc.stdout.off('data', onData);
        resolve(true);
      };
      stack.proc.stdout.on('data', onData);
      setTimeout(() => { stack.proc.stdout.off('data', onData); resolve(false); }, 10_000);
    });
    process.kill(old, 'SIGKILL');
    assert.ok(await waiting, `the restart is announced:\n${logSince(stack, from)}`);
    const t0 = Date.now();
    stack.proc.kill('SIGINT');
    const code = await exited;
    const stop = (Date.now() - t0) / 1000;
    t.diagnostic(`stopped in ${stop} s`);
    assert.equal(code, 0);
    assert.ok(stop < 5, `stopped in ${stop} s`);
    assert.doesNotMatch(logSince(stack, from), /starting bff again/, 'the pending restart was dropped');
    assert.deepEqual(describePids(pidsOfStack(env.DATA_DIR)), [], 'no process of the stack is left');
    assert.deepEqual(describePids(pidsWithEnv(marker)), []);
    for (const p of [BASE, BASE + 1, BASE + 2, BASE + 3]) assert.ok(await portFree(p), `port ${p} is free again`);
    t.diagnostic(`recovery after SIGKILL: ${Object.entries(took).map(([k, v]) => `${k} ${v} s`).join(', ')}`);
  });
});

test('a crash loop (the BFF cannot get its port): the supervisor gives up with a clear message, exit 1, nothing left', { timeout: 120_000 }, async (t) => {
  const env = stackEnv({ port: LOOP_BASE, masterPort: LOOP_BASE + 1, rosbridgePort: LOOP_BASE + 2, extraEnv: { UR_SIM: '0' } });
  // The port is taken (by us): every BFF start dies at once with EADDRINUSE.
  const holder = net.createServer((s) => s.destroy());
  await new Promise((r) => holder.listen(LOOP_BASE, '0.0.0.0', r));
  t.after(() => holder.close());
  let marker = null;
  t.after(() => killLeftovers(env, marker));
  const t0 = Date.now();
  const failure = await startStack(env, 90_000).then(() => null, (e) => e);
  const gaveUpAfter = (Date.now() - t0) / 1000;
  assert.ok(failure, 'the stack never gets ready');
  // The whole log (the error message holds only its end): startStack copies it to DATA_DIR/stack.log.
  const logFile = `${env.DATA_DIR}/stack.log`;
  await until(() => /\[stack\] stopped/.test(read0(logFile)), 5000);
  const out = `${failure.message}\n${read0(logFile)}`;
  t.diagnostic(`gave up after ${gaveUpAfter} s`);
  assert.match(out, /stack exited \(1\)/, 'exit code 1: systemd (Restart=on-failure) takes over');
  assert.match(out, /\[stack\] giving up: bff crashed 5 times in 60 s; last exit 1; see the lines above/);
  for (const [k, delay] of [[1, 'at once'], [2, 'in 0\\.5 s'], [3, 'in 1 s'], [4, 'in 2 s']]) {
    assert.match(out, new RegExp(`\\[stack\\] bff exited \\(1\\); restarting ${delay} \\(crash ${k} of 5 in 60 s\\)`));
  }
  assert.match(out, /EADDRINUSE/, 'the reason is in the lines above');
  assert.deepEqual(describePids(pidsOfStack(env.DATA_DIR)), [], 'no process of the stack is left');
  for (const p of [LOOP_BASE + 1, LOOP_BASE + 2, LOOP_BASE + 3]) assert.ok(await portFree(p), `port ${p} is free again`);
});

test('a configuration error of a child (exit code 2: an unsafe users file) is not restarted: the stack stops at once with exit 2', { timeout: 120_000 }, async (t) => {
  const env = stackEnv({ port: LOOP_BASE, masterPort: LOOP_BASE + 1, rosbridgePort: LOOP_BASE + 2, extraEnv: { UR_SIM: '0' } });
  addUser(env, 'admin', 'admin', 'admin-password');
  fs.chmodSync(`${env.DATA_DIR}/users.json`, 0o666);
  t.after(() => killLeftovers(env, null));
  const failure = await startStack(env, 90_000).then(() => null, (e) => e);
  assert.ok(failure, 'the stack never gets ready');
  const logFile = `${env.DATA_DIR}/stack.log`;
  await until(() => /\[stack\] stopped/.test(read0(logFile)), 5000);
  const out = `${failure.message}\n${read0(logFile)}`;
  assert.match(out, /stack exited \(2\)/);
  assert.match(out, /users\.json is group- or world-writable/);
  assert.match(out, /\[stack\] bff exited \(2\): a configuration error \(see above\); not restarting it/);
  assert.doesNotMatch(out, /restarting in/);
  assert.deepEqual(describePids(pidsOfStack(env.DATA_DIR)), [], 'no process of the stack is left');
});
