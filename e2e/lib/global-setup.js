import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import yaml from 'js-yaml';
import { stackEnv, addUser, startStack, REPO_ROOT } from './stack.js';

/**
 * One stack for a Playwright run, of the cell file E2E_CELL_CONFIG (default: the demo cell), with one user per role
 * of that cell file, named after the role (password `<role>-e2e-password`).
 */
export default async function globalSetup() {
  const port = Number(process.env.E2E_PORT || 18080);
  const cellConfig = path.resolve(REPO_ROOT, process.env.E2E_CELL_CONFIG || 'config/demo-cell.yaml');
  const cell = /** @type {any} */ (yaml.load(fs.readFileSync(cellConfig, 'utf8')));
  // A directory stands for the robot PC's USB mount points (the database tests plug a "drive" in there).
  const usbRoot = fs.mkdtempSync(path.join(os.tmpdir(), 'cell-usb-'));
  process.env.USB_ROOTS = usbRoot;
  const env = stackEnv({
    port, masterPort: port + 1, rosbridgePort: port + 2, ...(process.env.E2E_UR_HOST ? { urHost: process.env.E2E_UR_HOST } : {}),
    // The simulated cell runs as under `npm start` (the manual-motion tests drive it through the real driver).
    extraEnv: {
      CELL_CONFIG: cellConfig,
      // Per-arm controller addresses of a cell with several arms (group=host,...), away from other stacks'.
      ...(process.env.E2E_UR_HOSTS ? { UR_HOSTS: process.env.E2E_UR_HOSTS } : {}),
    },
  });
  const users = Object.fromEntries(Object.keys(cell.roles).map((role) => [role, `${role}-e2e-password`]));
  for (const [name, pw] of Object.entries(users)) addUser(env, name, name, pw);
  const stack = await startStack(env);
  process.env.E2E_ROS_MASTER_URI = env.ROS_MASTER_URI;
  process.env.E2E_ROSBRIDGE_URL = `ws://127.0.0.1:${env.ROSBRIDGE_PORT}`;
  process.env.E2E_USERS = JSON.stringify(users);
  process.env.E2E_DATA_DIR = env.DATA_DIR;
  process.env.E2E_PLANT_BROKER_URL = env.PLANT_BROKER_URL;
  process.env.E2E_CELL_CONFIG = cellConfig;
  globalThis.__cellStack = stack;
}
