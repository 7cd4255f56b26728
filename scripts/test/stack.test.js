// `npm start`'s supervisor: a whole stack comes up on isolated ports, SIGINT/SIGTERM stop every process it
// started within 5 s with no orphans, and a second start right after works.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import net from 'node:net';
import https from 'node:https';
import { stackEnv, addUser, startStack, stopStack, pidsOfStack, REPO_ROOT } from '../../e2e/lib/stack.js';

const portFree = (port) => new Promise((resolve) => {
  const s = net.createServer().once('error', () => resolve(false)).listen(port, '127.0.0.1', () => s.close(() => resolve(true)));
});

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
      assert.deepEqual(pidsOfStack(env.DATA_DIR), [], 'no process of the stack is left');
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
  // ...and the simulated cell publishes joint states on the stack's ROS master.
  const { execFile } = await import('node:child_process');
  const out = await new Promise((resolve, reject) => execFile('bash', ['-c', 'source scripts/ros-env.sh && rostopic echo -n 1 /joint_states/name'],
    { cwd: REPO_ROOT, env, timeout: 60_000 }, (e, stdout) => (e ? reject(e) : resolve(stdout))));
  assert.match(out, /shoulder_pan_joint/);
  const t0 = Date.now();
  await stopStack(stack.proc);
  assert.ok((Date.now() - t0) / 1000 < 5);
  assert.deepEqual(pidsOfStack(env.DATA_DIR), []);
});
