// Test helpers: a BFF on an ephemeral port with its own DATA_DIR.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import http from 'node:http';
import { readEnv } from '../src/core/config/env.js';
import { createBff } from '../src/app.js';

export function tempDir(prefix = 'bff-test-') {
  return fs.mkdtempSync(path.join(os.tmpdir(), prefix));
}

/** @param {Partial<Record<string,string>>} [extraEnv] @param {Parameters<typeof createBff>[1]} [opts] */
export async function startBff(extraEnv = {}, opts = {}) {
  const dataDir = tempDir();
  const appDir = path.join(dataDir, 'app');
  fs.mkdirSync(path.join(appDir, '_app/immutable'), { recursive: true });
  fs.writeFileSync(path.join(appDir, 'index.html'), '<!doctype html><title>shell</title>');
  fs.writeFileSync(path.join(appDir, '_app/immutable/entry.abc123.js'), 'export {}');
  fs.writeFileSync(path.join(appDir, 'sw.js'), '// sw');
  const env = readEnv({ DATA_DIR: dataDir, APP_DIR: appDir, ROSBRIDGE_PORT: '1', ROS_MASTER_URI: 'http://127.0.0.1:1',
    // Not the demo's broker (a developer's `npm start` may run one): these BFFs must not report as its cells.
    PLANT_BROKER_URL: 'mqtt://127.0.0.1:1', ...extraEnv });
  const bff = await createBff(env, { log: () => {}, ...opts });
  const server = http.createServer(bff.app);
  server.on('upgrade', (req, socket, head) => bff.relay.handleUpgrade(req, socket, head));
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  bff.lease.listening();
  const base = `http://127.0.0.1:${server.address().port}`;
  const passwords = Object.fromEntries((bff.initial?.users ?? []).map((u) => [u.username, u.password]));
  return {
    env, bff, base, passwords, dataDir,
    async stop() {
      bff.close();
      server.closeAllConnections();
      await new Promise((r) => server.close(r));
    },
  };
}

/** @param {string} base @param {string} username @param {string} password */
export async function login(base, username, password) {
  const res = await fetch(`${base}/api/auth/login`, {
    method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ username, password }),
  });
  const setCookie = res.headers.get('set-cookie') || '';
  return { res, cookie: setCookie.split(';')[0], setCookie };
}
