// Talking to the stack's ROS side from tests, as an engineer would from a terminal.
import { expect } from '@playwright/test';
import { execFile, spawn } from 'node:child_process';
import { promisify } from 'node:util';
import { REPO_ROOT } from './stack.js';

const run = promisify(execFile);

/** Run a ROS command line tool in the project's ROS environment against the e2e stack's master. */
export function rosCli(command) {
  return run('bash', ['-c', `source scripts/ros-env.sh && ${command}`], {
    cwd: REPO_ROOT, env: { ...process.env, ROS_MASTER_URI: process.env.E2E_ROS_MASTER_URI }, timeout: 30_000,
  });
}

/**
 * A ROS command line tool left running (e.g. `rostopic pub -r 20 ...`), in its own process group.
 * @param {string} command
 * @returns {{ kill: (signal?: NodeJS.Signals) => void }}
 */
export function rosCliRunning(command) {
  const proc = spawn('bash', ['-c', `source scripts/ros-env.sh && exec ${command}`], {
    cwd: REPO_ROOT, env: { ...process.env, ROS_MASTER_URI: process.env.E2E_ROS_MASTER_URI }, stdio: 'ignore', detached: true,
  });
  return {
    kill: (signal = 'SIGINT') => {
      try {
        process.kill(-(/** @type {number} */ (proc.pid)), signal);
      } catch { /* already gone */ }
    },
  };
}

/** @param {string} mode */
export function publishMode(mode) {
  return rosCli(`rostopic pub -1 /cell/mode cell_msgs/OperationMode "{mode: ${mode}, source: e2e}"`);
}

/** A device fault of the simulated cell (/sim/trigger_fault stands for a real device); 'reset' ends it. @param {string} f */
export const simFault = (f) => rosCli(`rosservice call /sim/trigger_fault "fault: '${f}'"`);

/**
 * The cell as the next spec expects it: the sim's faults gone and the alarm reset (once inactive, Reset clears it).
 * @param {string} [alarmId] the alarm that must be gone from the list
 */
export async function clearSimFault(alarmId = 'device.gripper_fault') {
  await simFault('reset');
  await expect.poll(async () => {
    await rosCli('rosservice call /cell/alarms/reset');
    return (await rosCli('rostopic echo -n1 /cell/alarms/list')).stdout.includes(alarmId);
  }, { timeout: 30_000, message: `the alarm ${alarmId} reset` }).toBe(false);
}

/**
 * No recording waiting for its seconds after an alarm (the flight recorder's /cell/recorder/state): a spec that raised
 * an alarm leaves the recorder as the next one expects it (the Recordings spec counts the recordings that appear).
 */
export async function recorderIdle() {
  await expect.poll(async () => {
    const out = (await rosCli('rostopic echo -n1 /cell/recorder/state')).stdout;
    return /^pending: ''$/m.test(out) || /^pending: ""$/m.test(out);
  }, { timeout: 40_000, intervals: [1000], message: 'the flight recorder has written the recording of the alarm' }).toBe(true);
}

/** XML-RPC call with string arguments; returns the raw response body. */
async function xmlrpc(uri, method, ...args) {
  const params = args.map((a) => `<param><value><string>${a}</string></value></param>`).join('');
  const res = await fetch(uri, { method: 'POST', headers: { 'content-type': 'text/xml' },
    body: `<?xml version="1.0"?><methodCall><methodName>${method}</methodName><params>${params}</params></methodCall>` });
  return res.text();
}

/** The pid of a ROS node, asked from the master and the node itself. @param {string} node */
export async function nodePid(node) {
  const lookup = await xmlrpc(process.env.E2E_ROS_MASTER_URI, 'lookupNode', '/e2e', node);
  const uri = lookup.match(/<string>(https?:\/\/[^<]+)<\/string>/)?.[1];
  if (!uri) return null;
  try {
    // getPid answers [code, statusMessage, pid]: the pid is the last integer.
    const ints = [...(await xmlrpc(uri, 'getPid', '/e2e')).matchAll(/<(?:int|i4)>(\d+)<\/(?:int|i4)>/g)].map((m) => Number(m[1]));
    const [code, pid] = [ints[0], ints[ints.length - 1]];
    return code === 1 && ints.length >= 2 && pid > 1 ? pid : null;
  } catch {
    return null;
  }
}
