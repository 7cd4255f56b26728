import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { stackEnv, addUser, startStack } from './stack.js';

export default async function globalSetup() {
  const port = Number(process.env.E2E_PORT || 18080);
  // A directory stands for the robot PC's USB mount points (the database tests plug a "drive" in there).
  const usbRoot = fs.mkdtempSync(path.join(os.tmpdir(), 'cell-usb-'));
  process.env.USB_ROOTS = usbRoot;
  const env = stackEnv({
    port, masterPort: port + 1, rosbridgePort: port + 2, ...(process.env.E2E_UR_HOST ? { urHost: process.env.E2E_UR_HOST } : {}),
    // The simulated cell runs as under `npm start` (the manual-motion tests drive it through the real driver).
  });
  const users = { admin: 'admin-e2e-password', operator: 'operator-e2e-password' };
  for (const [name, pw] of Object.entries(users)) addUser(env, name, name, pw);
  const stack = await startStack(env);
  process.env.E2E_ROS_MASTER_URI = env.ROS_MASTER_URI;
  process.env.E2E_ROSBRIDGE_URL = `ws://127.0.0.1:${env.ROSBRIDGE_PORT}`;
  process.env.E2E_USERS = JSON.stringify(users);
  process.env.E2E_DATA_DIR = env.DATA_DIR;
  globalThis.__cellStack = stack;
}
