// A second cell on the e2e stack's plant broker: the twin cell's BFF as its own process (its ROS side is not
// started: the plant page shows that cell with its ROS link down).
import { spawn } from 'node:child_process';
import net from 'node:net';
import path from 'node:path';
import { stackEnv, addUser, REPO_ROOT } from './stack.js';

/** @returns {Promise<number>} */
export const freePort = () => new Promise((resolve) => {
  const s = net.createServer().listen(0, '127.0.0.1', () => { const a = /** @type {net.AddressInfo} */ (s.address()); s.close(() => resolve(a.port)); });
});

/** @param {string} cellFile relative to the repository @param {string} broker */
export async function otherCell(cellFile, broker) {
  const port = await freePort();
  const env = stackEnv({
    port, masterPort: await freePort(), rosbridgePort: await freePort(),
    extraEnv: { CELL_CONFIG: path.join(REPO_ROOT, cellFile), TLS_PORT: String(await freePort()), PLANT_BROKER_URL: broker, BFF_HOST: '127.0.0.1' },
  });
  addUser(env, 'admin', 'admin', 'admin-e2e-password');
  const proc = spawn(process.execPath, ['bff/src/server.js'], { cwd: REPO_ROOT, env, stdio: 'ignore' });
  const base = `http://127.0.0.1:${port}`;
  const end = Date.now() + 20_000;
  while (!(await fetch(`${base}/api/health`).then((r) => r.ok, () => false))) {
    if (proc.exitCode !== null || Date.now() > end) throw new Error(`${cellFile}'s BFF did not start (exit ${proc.exitCode})`);
    await new Promise((r) => setTimeout(r, 100));
  }
  return { base, stop: () => proc.kill('SIGKILL') };
}
