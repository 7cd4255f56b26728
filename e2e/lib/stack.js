// Starts and stops a whole stack (scripts/stack.js) on isolated ports, as `npm start` would.
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const REPO_ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');

/**
 * @param {{port: number, masterPort: number, rosbridgePort: number, urHost?: string, extraEnv?: Record<string,string>}} o
 */
export function stackEnv({ port, masterPort, rosbridgePort, urHost = '127.0.0.9', extraEnv = {} }) {
  const dataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'cell-stack-'));
  return {
    ...process.env,
    PORT: String(port),
    TLS_PORT: String(port + 3),
    ROS_MASTER_URI: `http://127.0.0.1:${masterPort}`,
    ROSBRIDGE_PORT: String(rosbridgePort),
    DATA_DIR: dataDir,
    UR_HOST: urHost,
    // The plant's broker for this stack (the stack starts mosquitto there when its cell file has a plant section).
    PLANT_BROKER_URL: `mqtt://127.0.0.1:${port + 6}`,
    PLANT_CELL_URL: `http://127.0.0.1:${port}/`,
    ...extraEnv,
  };
}

/** Create users with known passwords before the first start (so no random ones are generated). */
export function addUser(env, name, role, password) {
  const r = spawnSync(process.execPath, ['bff/src/cli/users.js', 'add', name, '--role', role, '--password-stdin'],
    { cwd: REPO_ROOT, env, input: password, encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`users add ${name}: ${r.stderr}`);
}

/** @param {NodeJS.ProcessEnv} env @param {number} timeoutMs */
export async function startStack(env, timeoutMs = 90_000) {
  const proc = spawn(process.execPath, ['scripts/stack.js'], { cwd: REPO_ROOT, env, stdio: ['ignore', 'pipe', 'pipe'] });
  let output = '';
  const logFile = path.join(env.DATA_DIR, 'stack.log');
  const sink = fs.createWriteStream(logFile);
  proc.stdout.on('data', (d) => { output += d; sink.write(d); });
  proc.stderr.on('data', (d) => { output += d; sink.write(d); });
  const end = Date.now() + timeoutMs;
  while (!/\[stack\] ready:/.test(output)) {
    if (proc.exitCode !== null) throw new Error(`stack exited (${proc.exitCode}):\n${output.slice(-3000)}`);
    if (Date.now() > end) { proc.kill('SIGINT'); throw new Error(`stack not ready in time:\n${output.slice(-3000)}`); }
    await new Promise((r) => setTimeout(r, 100));
  }
  return { proc, logFile, output: () => output };
}

/** SIGINT the supervisor and wait for it; returns the seconds it took. @param {import('node:child_process').ChildProcess} proc */
export async function stopStack(proc, timeoutMs = 10_000) {
  const t0 = Date.now();
  if (proc.exitCode === null && proc.signalCode === null) {
    const exited = new Promise((r) => proc.once('exit', r));
    proc.kill('SIGINT');
    await Promise.race([exited, new Promise((r) => setTimeout(r, timeoutMs))]);
  }
  return (Date.now() - t0) / 1000;
}

/** Pids of processes whose environment names this stack's DATA_DIR. @param {string} dataDir */
export function pidsOfStack(dataDir) {
  const pids = [];
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d) || Number(d) === process.pid) continue;
    try {
      const environ = fs.readFileSync(`/proc/${d}/environ`, 'utf8').split('\0');
      const stat = fs.readFileSync(`/proc/${d}/stat`, 'utf8');
      if (environ.includes(`DATA_DIR=${dataDir}`) && !/\) Z /.test(stat)) pids.push(Number(d));
    } catch { /* gone */ }
  }
  return pids;
}
