// `npm start`'s supervisor: a whole stack comes up on isolated ports, SIGINT/SIGTERM stop every process it
// started within 5 s with no orphans, and a second start right after works. Even a SIGKILLed supervisor
// (up, or still starting its children) leaves nothing behind: its watchdog stops the stack within 5 s.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import net from 'node:net';
import https from 'node:https';
import { stackEnv, addUser, startStack, stopStack, pidsOfStack, REPO_ROOT } from '../../e2e/lib/stack.js';

const portFree = (port) => new Promise((resolve) => {
  const s = net.createServer().once('error', () => resolve(false)).listen(port, '127.0.0.1', () => s.close(() => resolve(true)));
});

/** Poll `pred` every 50 ms until it holds or `ms` have passed; true if it held. */
async function until(pred, ms) {
  const end = Date.now() + ms;
  for (;;) {
    if (await pred()) return true;
    if (Date.now() >= end) return false;
    await new Promise((r) => setTimeout(r, 50));
  }
}

const environOf = (pid) => { try { return fs.readFileSync(`/proc/${pid}/environ`, 'utf8').split('\0'); } catch { return []; } };
const describe = (pids) => pids.map((p) => { try { return `${p}: ${fs.readFileSync(`/proc/${p}/cmdline`, 'utf8').replace(/\0/g, ' ').trim()}`; } catch { return `${p}: (gone)`; } });

/** Live (non-zombie) pids whose environment holds exactly `entry` (e.g. `CELL_STACK_ID=...`). */
function pidsWithEnv(entry) {
  const pids = [];
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d) || Number(d) === process.pid) continue;
    try {
      if (environOf(d).includes(entry) && !/\) Z /.test(fs.readFileSync(`/proc/${d}/stat`, 'utf8'))) pids.push(Number(d));
    } catch { /* gone */ }
  }
  return pids;
}

/** The stack's marker (`CELL_STACK_ID=...`), read from one of its running children. */
function markerOf(dataDir) {
  for (const pid of pidsOfStack(dataDir)) {
    const entry = environOf(pid).find((e) => e.startsWith('CELL_STACK_ID='));
    if (entry) return entry;
  }
  return null;
}

/** SIGKILL the supervisor alone (not its group) and wait up to 5 s for everything of its stack to be gone. */
async function killSupervisorAndAwaitCleanup(proc, env, marker, ports) {
  const stackPids = () => [...new Set([...pidsWithEnv(marker), ...pidsOfStack(env.DATA_DIR)])];
  const before = stackPids();
  const exited = new Promise((r) => proc.once('exit', r));
  const t0 = Date.now();
  process.kill(proc.pid, 'SIGKILL');
  await exited;
  const clean = async () => stackPids().length === 0 && (await Promise.all(ports.map(portFree))).every(Boolean);
  const ok = await until(clean, 5000 - (Date.now() - t0));
  const took = (Date.now() - t0) / 1000;
  assert.deepEqual(describe(stackPids()), [], `no process of the stack is left ${took} s after the SIGKILL (had ${before.length})`);
  for (const p of ports) assert.ok(await portFree(p), `port ${p} is free again ${took} s after the SIGKILL`);
  assert.ok(ok, `cleaned up in ${took} s`);
  return took;
}

/** Whatever a failed run left behind must not outlive the test. */
function killLeftovers(env, marker) {
  for (const pid of [...pidsOfStack(env.DATA_DIR), ...(marker ? pidsWithEnv(marker) : [])]) {
    try { process.kill(pid, 'SIGKILL'); } catch { /* gone */ }
  }
}

for (const signal of ['SIGINT', 'SIGTERM']) {
  test(`start, serve, stop on ${signal} within 5 s with nothing left behind, start again`, { timeout: 240_000 }, async (t) => {
    const base = signal === 'SIGINT' ? 28080 : 28180;
    const env = stackEnv({ port: base, masterPort: base + 1, rosbridgePort: base + 2, extraEnv: { UR_SIM: '0' } });
    addUser(env, 'admin', 'admin', 'admin-password');
    for (let round = 1; round <= 2; round++) {
      const stack = await startStack(env);
      t.after(() => stopStack(stack.proc));
      const health = await (await fetch(`http://127.0.0.1:${base}/api/health`)).json();
      assert.deepEqual(health.ros, { master: true, rosbridge: true }, `round ${round}`);
      if (round === 1) {
        // HTTPS for phones: the CA from /ca.crt is all a client needs to trust the cell's HTTPS port.
        const ca = await (await fetch(`http://127.0.0.1:${base}/ca.crt`)).text();
        assert.match(ca, /BEGIN CERTIFICATE/);
        const status = await new Promise((resolve, reject) => {
          https.get({ host: '127.0.0.1', port: base + 3, path: '/api/health', ca }, (res) => { res.resume(); resolve(res.statusCode); }).on('error', reject);
        });
        assert.equal(status, 200);
      }
      const before = pidsOfStack(env.DATA_DIR);
      assert.ok(before.length >= 5, `roscore, rosmaster, rosout, roslaunch, nodes, BFF: saw ${before.length}`);

      const t0 = Date.now();
      const exited = new Promise((r) => stack.proc.once('exit', r));
      stack.proc.kill(signal);
      await exited;
      const took = (Date.now() - t0) / 1000;
      assert.ok(took < 5, `stopped in ${took} s`);
      // Within the same 5 s nothing of the stack is left (the detached watchdog exits just after its check).
      await until(() => pidsOfStack(env.DATA_DIR).length === 0, 5000 - (Date.now() - t0));
      assert.deepEqual(describe(pidsOfStack(env.DATA_DIR)), [], `no process of the stack is left ${(Date.now() - t0) / 1000} s after the ${signal}`);
      for (const p of [base, base + 1, base + 2, base + 3]) assert.ok(await portFree(p), `port ${p} is free again`);
    }
  });
}

test('a bad cell file stops the start with the field named and exit code 2', { timeout: 60_000 }, async () => {
  const env = stackEnv({ port: 28280, masterPort: 28281, rosbridgePort: 28282, extraEnv: { CELL_CONFIG: '/nonexistent/cell.yaml' } });
  await assert.rejects(startStack(env, 20_000), /cannot read: ENOENT[\s\S]*exited \(2\)|exited \(2\)[\s\S]*cannot read/);
  assert.deepEqual(pidsOfStack(env.DATA_DIR), []);
});

test('npm start runs the simulated cell by default, at UR_HOST, and stops it with the rest', { timeout: 180_000 }, async (t) => {
  const base = 28380;
  const urHost = '127.0.0.21';
  const env = stackEnv({ port: base, masterPort: base + 1, rosbridgePort: base + 2, urHost, extraEnv: { SIM_ARGS: '--no-cameras' } });
  delete env.UR_SIM;
  const stack = await startStack(env);
  t.after(() => stopStack(stack.proc));
  // The UR dashboard server answers at UR_HOST like a real controller...
  const greeting = await new Promise((resolve, reject) => {
    const s = net.connect({ host: urHost, port: 29999 });
    s.setTimeout(20_000, () => reject(new Error('no dashboard greeting')));
    s.once('data', (d) => { s.destroy(); resolve(d.toString()); });
    s.once('error', reject);
  });
  assert.match(greeting, /Universal Robots Dashboard Server/);
  // ...and the robot driver (features/manual.launch) reads it over RTDE and publishes joint states on the stack's master.
  const { execFile } = await import('node:child_process');
  const out = await new Promise((resolve, reject) => execFile('bash', ['-c', 'source scripts/ros-env.sh && rostopic echo -n 1 /joint_states/name'],
    { cwd: REPO_ROOT, env, timeout: 60_000 }, (e, stdout) => (e ? reject(e) : resolve(stdout))));
  assert.match(out, /shoulder_pan_joint/);
  const t0 = Date.now();
  await stopStack(stack.proc);
  assert.ok((Date.now() - t0) / 1000 < 5);
  assert.deepEqual(pidsOfStack(env.DATA_DIR), []);
});

test('SIGKILL of the supervisor alone, once up: master, nodes, BFF and ports are gone within 5 s; a stack beside it lives on', { timeout: 240_000 }, async (t) => {
  const base = 28480;
  const ports = [base, base + 1, base + 2, base + 3];
  const env = stackEnv({ port: base, masterPort: base + 1, rosbridgePort: base + 2, extraEnv: { UR_SIM: '0' } });
  const otherEnv = stackEnv({ port: 28680, masterPort: 28681, rosbridgePort: 28682, extraEnv: { UR_SIM: '0' } });
  let marker = null;
  t.after(() => killLeftovers(env, marker));
  t.after(() => killLeftovers(otherEnv, null));
  const [stack, other] = await Promise.all([startStack(env), startStack(otherEnv)]);
  t.after(() => stopStack(stack.proc));
  t.after(() => stopStack(other.proc));
  const health = await (await fetch(`http://127.0.0.1:${base}/api/health`)).json();
  assert.deepEqual(health.ros, { master: true, rosbridge: true });
  for (const p of ports) assert.equal(await portFree(p), false, `port ${p} is listening`);
  marker = markerOf(env.DATA_DIR);
  assert.match(marker ?? '', /^CELL_STACK_ID=\S+$/);
  assert.ok(pidsWithEnv(marker).length >= 5, 'roscore, rosmaster, rosout, roslaunch, nodes, BFF carry the marker');
  const otherPids = pidsOfStack(otherEnv.DATA_DIR);

  const took = await killSupervisorAndAwaitCleanup(stack.proc, env, marker, ports);
  t.diagnostic(`cleaned up in ${took} s; ${stack.output().match(/^\[watchdog\].*/gm)?.join(' / ')}`);

  // The other stack lost nothing and still serves; it stops cleanly as ever.
  assert.deepEqual(describe(otherPids.filter((p) => !pidsOfStack(otherEnv.DATA_DIR).includes(p))), [], 'the other stack lost no process');
  const otherHealth = await (await fetch('http://127.0.0.1:28680/api/health')).json();
  assert.deepEqual(otherHealth.ros, { master: true, rosbridge: true });
  assert.ok((await stopStack(other.proc)) < 5);
  assert.deepEqual(pidsOfStack(otherEnv.DATA_DIR), []);
});

test('SIGKILL of the supervisor while it is still starting its children leaves nothing behind', { timeout: 180_000 }, async (t) => {
  const base = 28580;
  const ports = [base, base + 1, base + 2, base + 3];
  const env = stackEnv({ port: base, masterPort: base + 1, rosbridgePort: base + 2, extraEnv: { UR_SIM: '0' } });
  let marker = null;
  t.after(() => killLeftovers(env, marker));
  const proc = spawn(process.execPath, ['scripts/stack.js'], { cwd: REPO_ROOT, env, stdio: ['ignore', 'pipe', 'pipe'] });
  t.after(() => stopStack(proc));
  let output = '';
  proc.stdout.on('data', (d) => { output += d; });
  proc.stderr.on('data', (d) => { output += d; });
  // roscore is up and roslaunch has just begun bringing up its nodes; the BFF has just been spawned.
  const starting = await until(() => /^\[ros\] /m.test(output) || proc.exitCode !== null, 60_000);
  assert.ok(starting && proc.exitCode === null, `roslaunch starts:\n${output.slice(-2000)}`);
  assert.doesNotMatch(output, /\[stack\] ready:/);
  marker = markerOf(env.DATA_DIR);
  assert.match(marker ?? '', /^CELL_STACK_ID=\S+$/);
  const took = await killSupervisorAndAwaitCleanup(proc, env, marker, ports);
  t.diagnostic(`cleaned up in ${took} s; ${output.match(/^\[watchdog\].*/gm)?.join(' / ')}`);
});

test('output nobody reads: the stack still starts, restarts a child and stops within 5 s; queued lines arrive once read', { timeout: 240_000 }, async (t) => {
  const base = 28980;
  const ports = [base, base + 1, base + 2, base + 3];
  const env = stackEnv({ port: base, masterPort: base + 1, rosbridgePort: base + 2, extraEnv: { UR_SIM: '0' } });
  let marker = null;
  t.after(() => killLeftovers(env, marker));
  // A pipe that is full before the stack starts, and that nobody reads: what a stuck log collector looks like.
  // The stack writes to it through its own blocking descriptor; the test reads and fills it through another.
  const fifo = `${env.DATA_DIR}/output.fifo`;
  spawnSync('mkfifo', [fifo]);
  const mine = fs.openSync(fifo, fs.constants.O_RDWR | fs.constants.O_NONBLOCK);
  const theirs = fs.openSync(fifo, fs.constants.O_WRONLY);
  t.after(() => { fs.closeSync(mine); });
  const fill = () => { let n = 0; try { for (;;) n += fs.writeSync(mine, Buffer.alloc(4096, '.')); } catch (e) { if (e.code !== 'EAGAIN') throw e; } return n; };
  assert.ok(fill() >= 4096, 'the pipe is full');
  const proc = spawn(process.execPath, ['scripts/stack.js'], { cwd: REPO_ROOT, env, stdio: ['ignore', theirs, theirs] });
  fs.closeSync(theirs);
  t.after(() => stopStack(proc));
  const health = async () => { try { return await (await fetch(`http://127.0.0.1:${base}/api/health`, { signal: AbortSignal.timeout(2000) })).json(); } catch { return null; } };

  // Up, with its output stalled from the first line on (the supervisor used to block on that line for ever).
  assert.ok(await until(async () => (await health())?.ros?.rosbridge === true, 90_000), 'the stack comes up and rosbridge answers');
  marker = markerOf(env.DATA_DIR);
  // Still supervising: a killed BFF is restarted (its exit and restart are logged into the stalled pipe).
  const bffPid = () => pidsOfStack(env.DATA_DIR).find((p) => /bff\/src\/server\.js/.test(fs.readFileSync(`/proc/${p}/cmdline`, 'utf8')));
  const first = bffPid();
  assert.ok(first, 'the BFF runs');
  process.kill(first, 'SIGKILL');
  assert.ok(await until(async () => { const p = bffPid(); return !!p && p !== first && (await health())?.ros?.rosbridge === true; }, 60_000),
    'the BFF is restarted and answers');

  // Once read, the queued lines come through, in order, up to the restart.
  let text = '';
  const drain = () => { const buf = Buffer.alloc(65536); try { for (;;) { const n = fs.readSync(mine, buf); if (!n) break; text += buf.subarray(0, n).toString(); } } catch (e) { if (e.code !== 'EAGAIN') throw e; } };
  assert.ok(await until(() => { drain(); return /\[stack\] starting bff again/.test(text); }, 20_000), `the queued lines arrive:\n${text.replace(/^\.+/, '').slice(-1500)}`);
  const lines = text.replace(/^\.+/, '').split('\n');
  const at = (re) => lines.findIndex((l) => re.test(l));
  const order = [/^\[stack\] starting roscore/, /^\[bff\] listening on http:/, /^\[stack\] bff exited \(SIGKILL\)/, /^\[stack\] starting bff again/];
  const seen = order.map(at);
  assert.ok(seen.every((i, k) => i >= 0 && (k === 0 || i > seen[k - 1])), `in order: ${order.map((re, k) => `${re.source} at ${seen[k]}`).join(', ')}`);

  // Stalled again: Ctrl-C still stops everything within 5 s.
  fill();
  const took = await (async () => { const t0 = Date.now(); await stopStack(proc, 10_000); return (Date.now() - t0) / 1000; })();
  assert.ok(proc.exitCode === 0, `the supervisor exited (${proc.exitCode ?? proc.signalCode})`);
  assert.ok(took < 5, `stopped in ${took} s with its output stalled`);
  // The contract is the whole stack gone within 5 s of Ctrl-C (README): what the supervisor's exit left of them.
  const left = () => pidsOfStack(env.DATA_DIR).map((p) => { try { return `${p} ${fs.readFileSync(`/proc/${p}/cmdline`, 'utf8').replace(/\0/g, ' ').slice(0, 120)}`; } catch { return `${p} (gone)`; } });
  assert.ok(await until(() => pidsOfStack(env.DATA_DIR).length === 0, Math.max(0, 5000 - took * 1000)),
    `nothing of the stack is left within 5 s of Ctrl-C: ${left().join('; ')}`);
  for (const p of ports) assert.ok(await portFree(p), `port ${p} is free again`);
});
