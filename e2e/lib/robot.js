// Watching an arm from outside the app, as an engineer would with `rostopic echo`: a plain rosbridge client
// on the stack's own rosbridge port (loopback, behind the BFF), subscribed to the driver's /joint_states (every
// arm publishes its own joints there, with the cell file's names) or to a group's /cell/manual/<group>/state.
// The group defaults to the first motion group of the cell file under test (E2E_CELL_CONFIG; the demo's `arm`).
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { WebSocket } from 'ws';
import { expect } from '@playwright/test';
import { REPO_ROOT } from './stack.js';

// A jog stopped: 50 consecutive /joint_states (0.4 s at 125 Hz) without joint motion. A jog that went on, even at
// a tenth of these tests' speed (0.05 rad/s), would travel 20 mrad in that time; the sim's stopped arm may still
// settle by up to about 1 mrad (CI saw 0.73 mrad with reported speeds under 3e-5 rad/s, and once a single reported
// speed of 1.2 mrad/s: PyBullet corrects contact and constraint errors mostly in position). So 2 mrad of travel,
// and no reported speed of 10 mrad/s or more (a fifth of that slowest jog).
export const STILL = { messages: 50, rad: 2e-3, speed: 1e-2 };

/** The motion groups of the cell file under test. @returns {{ name: string, joints: string[] }[]} */
export function cellGroups() {
  const file = path.resolve(REPO_ROOT, process.env.E2E_CELL_CONFIG || 'config/demo-cell.yaml');
  const cell = /** @type {any} */ (yaml.load(fs.readFileSync(file, 'utf8')));
  return cell?.manual?.groups ?? [];
}

/** @param {string} [group] @returns {{ name: string, joints: string[], ros_control?: { joint_states?: string } }} */
function groupOf(group) {
  const groups = cellGroups();
  const g = group === undefined ? groups[0] : groups.find((x) => x.name === group);
  if (!g) throw new Error(`no motion group ${group ?? '(none)'} in the cell file`);
  return g;
}

/**
 * @typedef {object} RobotWatch
 * @property {() => number[]} joints  the latest actual joint positions (rad)
 * @property {() => number} speed  the largest absolute joint velocity in the latest message (rad/s)
 * @property {(n: number) => Promise<Observation>} observe  the next n messages
 * @property {() => void} close
 */

/**
 * @typedef {object} Observation
 * @property {number} maxSpeed  the largest absolute joint velocity over the messages (rad/s)
 * @property {number} travel  the largest joint's distance from the first message to the last (rad)
 * @property {string} detail  per joint: its position, travel and largest speed, and how long the messages took
 *   (for a failure message: which joint moves, where, and whether it travels as fast as it reports)
 */

/**
 * One group's joints from /joint_states (the messages of its arm, in the group's joint order).
 * @param {string} [group] default: the cell's first group
 * @param {string} [url] e.g. ws://127.0.0.1:18082
 * @returns {Promise<RobotWatch>}
 */
export async function watchRobot(group, url = process.env.E2E_ROSBRIDGE_URL || '') {
  const g = groupOf(group);
  const { name: groupName, joints } = g;
  // A ros_control arm's own driver publishes its joint states (the cell file names the topic).
  const topic = g.ros_control?.joint_states ?? '/joint_states';
  const ws = new WebSocket(url);
  /** @type {{position: number[], velocity: number[]} | null} */
  let last = null;
  /** @type {Array<(m: {position: number[], velocity: number[]}) => void>} */
  let listeners = [];
  ws.on('message', (d) => {
    const m = JSON.parse(d.toString());
    if (m.op !== 'publish' || m.topic !== topic) return;
    // Several arms share the topic: keep this group's joints, in its order (skip another arm's message).
    const names = Array.isArray(m.msg?.name) ? m.msg.name : [];
    const idx = joints.map((j) => names.indexOf(j));
    if (idx.some((i) => i < 0)) return;
    const msg = { position: idx.map((i) => m.msg.position[i]), velocity: idx.map((i) => m.msg.velocity?.[i] ?? 0) };
    last = msg;
    for (const l of listeners) l(msg);
  });
  await new Promise((resolve, reject) => { ws.once('open', resolve); ws.once('error', reject); });
  ws.send(JSON.stringify({ op: 'subscribe', id: 'e2e-joints', topic, type: 'sensor_msgs/JointState' }));
  const first = Date.now();
  while (!last) {
    if (Date.now() - first > 20_000) throw new Error(`no ${topic} of group ${groupName} (${joints.join(', ')}) from the robot driver within 20 s`);
    await new Promise((r) => setTimeout(r, 20));
  }
  const now = () => /** @type {{position: number[], velocity: number[]}} */ (last);
  return {
    joints: () => [...now().position],
    speed: () => Math.max(...now().velocity.map(Math.abs)),
    observe: (n) => new Promise((resolve) => {
      const start = [...now().position];
      const t0 = Date.now();
      const peak = joints.map(() => 0);
      let seen = 0;
      /** @param {{position: number[], velocity: number[]}} m */
      const l = (m) => {
        m.velocity.forEach((v, i) => { peak[i] = Math.max(peak[i], Math.abs(v)); });
        if (++seen < n) return;
        listeners = listeners.filter((x) => x !== l);
        const moved = m.position.map((q, i) => Math.abs(q - start[i]));
        const detail = `${n} messages in ${Date.now() - t0} ms; ` + joints.map((j, i) =>
          `${j} at ${m.position[i].toFixed(4)}: travel ${moved[i].toExponential(2)}, speed up to ${peak[i].toExponential(3)}`).join('; ');
        resolve({ maxSpeed: Math.max(...peak), travel: Math.max(...moved), detail });
      };
      listeners.push(l);
    }),
    close: () => ws.close(),
  };
}

/**
 * @typedef {object} TcpWatch
 * @property {() => number[]} pose  the latest actual TCP pose (x, y, z m, rx, ry, rz rad)
 * @property {(target: number[], sinceMs?: number) => number} closest  the smallest distance (m) of the TCP to
 *   target's position among the samples taken since sinceMs (epoch ms; default all)
 * @property {() => void} close
 */

/**
 * A group's driver state (20 Hz, /cell/manual/<group>/state), kept as TCP samples.
 * @param {string} [group] default: the cell's first group
 * @param {string} [url]
 * @returns {Promise<TcpWatch>}
 */
export async function watchTcp(group, url = process.env.E2E_ROSBRIDGE_URL || '') {
  const topic = `/cell/manual/${groupOf(group).name}/state`;
  const ws = new WebSocket(url);
  /** @type {{ at: number, p: number[] }[]} */
  const samples = [];
  ws.on('message', (d) => {
    const m = JSON.parse(d.toString());
    if (m.op !== 'publish' || m.topic !== topic || !Array.isArray(m.msg?.tcp_pose) || m.msg.tcp_pose.length < 6) return;
    samples.push({ at: Date.now(), p: m.msg.tcp_pose });
    if (samples.length > 20_000) samples.splice(0, 10_000);
  });
  await new Promise((resolve, reject) => { ws.once('open', resolve); ws.once('error', reject); });
  ws.send(JSON.stringify({ op: 'subscribe', id: 'e2e-tcp', topic, type: 'cell_msgs/RobotState' }));
  const first = Date.now();
  while (!samples.length) {
    if (Date.now() - first > 20_000) throw new Error(`no ${topic} from the robot driver within 20 s`);
    await new Promise((r) => setTimeout(r, 20));
  }
  return {
    pose: () => [...samples[samples.length - 1].p],
    closest: (target, sinceMs = 0) => Math.min(...samples.filter((s) => s.at >= sinceMs)
      .map((s) => Math.hypot(s.p[0] - target[0], s.p[1] - target[1], s.p[2] - target[2]))),
    close: () => ws.close(),
  };
}

/**
 * The parts' world positions from the sim's ground truth (/sim/objects, 5 Hz; a real cell has no such topic), on
 * the stack's own rosbridge; `restock` puts every part back where it lay at the start (the sim's feeder, /sim/restock),
 * so a process spec can run again on the same stack (`--repeat-each`) with its cube away from its pocket.
 * @param {string} [url]
 * @returns {Promise<{ parts: () => {x: number, y: number, z: number}[], restock: () => Promise<void>, close: () => void }>}
 */
export async function watchParts(url = process.env.E2E_ROSBRIDGE_URL || '') {
  const ws = new WebSocket(url);
  /** @type {{x: number, y: number, z: number}[]} */
  let parts = [];
  /** @type {((m: any) => void) | null} */
  let restocked = null;
  let seen = 0;
  ws.on('message', (d) => {
    const m = JSON.parse(d.toString());
    if (m.op === 'publish' && m.topic === '/sim/objects') {
      parts = m.msg.poses.map((/** @type {any} */ p) => p.position);
      seen++;
    }
    if (m.op === 'service_response' && m.id === 'restock') restocked?.(m);
  });
  await new Promise((resolve, reject) => { ws.once('open', resolve); ws.once('error', reject); });
  ws.send(JSON.stringify({ op: 'subscribe', id: 'parts', topic: '/sim/objects', type: 'geometry_msgs/PoseArray' }));
  const first = Date.now();
  while (!parts.length) {
    if (Date.now() - first > 20_000) throw new Error('no /sim/objects from the simulated cell within 20 s');
    await new Promise((r) => setTimeout(r, 20));
  }
  const restock = async () => {
    const answer = /** @type {any} */ (await new Promise((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error('/sim/restock did not answer within 10 s')), 10_000);
      restocked = (m) => { clearTimeout(timer); resolve(m); };
      ws.send(JSON.stringify({ op: 'call_service', id: 'restock', service: '/sim/restock' }));
    }));
    if (answer.result !== true || answer.values?.success !== true) throw new Error(`/sim/restock: ${JSON.stringify(answer.values)}`);
    // The second /sim/objects message after the answer shows the parts where the feeder put them (the first may have
    // left the sim before the restock).
    const until = seen + 2;
    const since = Date.now();
    while (seen < until) {
      if (Date.now() - since > 5_000) throw new Error('no /sim/objects within 5 s of /sim/restock');
      await new Promise((r) => setTimeout(r, 20));
    }
  };
  return { parts: () => parts, restock, close: () => ws.close() };
}

/**
 * Wait for the arm to come to rest and stay at rest for STILL.messages joint states (within `timeout`). A release
 * that a stalled host delivers together with the heartbeats before it may first let the jog go on for a moment (the
 * driver jogs on when a stalled link's heartbeats come again, docs/ros-interfaces.md): CI once saw the arm at rest
 * at the release, then 0.14 rad/s. What must hold is that it stops and stays stopped; a jog that goes on never
 * shows a still window and fails here.
 * @param {import('./robot.js').RobotWatch} robot
 */
export async function expectStandstill(robot, timeout = 3_000) {
  const end = Date.now() + timeout;
  let after = await robot.observe(STILL.messages);
  while (!(after.travel < STILL.rad && after.maxSpeed < STILL.speed) && Date.now() < end) after = await robot.observe(STILL.messages);
  expect(after.travel, `travel over the last ${STILL.messages} joint states, ${timeout} ms after the release (${after.detail})`).toBeLessThan(STILL.rad);
  expect(after.maxSpeed, `the largest joint speed over those ${STILL.messages} joint states (${after.detail})`).toBeLessThan(STILL.speed);
}

/**
 * Wait for the arm to be at rest: over `messages` joint states in a row (within `timeout`), no joint travels `rad`
 * and none reports `speed` (the driver's own standstill, 0.01 rad/s: what the product waits for). A failure names
 * each joint's position, travel and speed.
 * @param {RobotWatch} robot
 * @param {{ rad?: number, speed?: number, messages?: number, timeout?: number }} [opts]
 */
export async function expectAtRest(robot, { rad = 1e-4, speed = STILL.speed, messages = 25, timeout = 10_000 } = {}) {
  const end = Date.now() + timeout;
  const still = (/** @type {Observation} */ o) => o.travel < rad && o.maxSpeed < speed;
  let o = await robot.observe(messages);
  while (!still(o) && Date.now() < end) o = await robot.observe(messages);
  expect(o.travel, `the largest joint travel over ${messages} joint states, after ${timeout} ms (${o.detail})`).toBeLessThan(rad);
  expect(o.maxSpeed, `the largest joint speed over those joint states (${o.detail})`).toBeLessThan(speed);
}

/**
 * Hold a jog button down (mouse: the pointer events a thumb would send) until the arm moves. A failure says what the
 * page showed meanwhile: whether the button still read as held, why the pad refused, the driver's motion and message.
 * @param {import('@playwright/test').Page} page @param {RobotWatch} robot @param {string} name
 */
export async function holdJog(page, robot, name) {
  const before = robot.joints();
  const button = page.getByRole('button', { name, exact: true });
  await button.hover();
  await page.mouse.down();
  const moved = () => Math.max(...robot.joints().map((q, i) => Math.abs(q - before[i])));
  // 15 s: the first command after the stack starts has the driver upload and start the control script first (CI:
  // 5.5 s from the press to the script running, on a loaded host), and a page still building its 3D view may not run
  // its heartbeat timer for seconds (the driver then stops the jog, and it goes on with the next heartbeat).
  try {
    await expect.poll(moved, { timeout: 15_000 }).toBeGreaterThan(0.01);
  } catch (e) {
    const read = async (/** @type {import('@playwright/test').Locator} */ l) => (await l.count()) ? (await l.first().innerText()).trim() : '-';
    const shown = [`button pressed: ${await button.getAttribute('aria-pressed')}`,
      `pad: ${await read(page.getByTestId('jog-blocked'))}`, `jog note: ${await read(page.getByTestId('jog-note'))}`,
      `motion: ${await read(page.getByTestId('manual-motion'))}`, `message: ${await read(page.getByTestId('manual-message'))}`];
    throw new Error(`${/** @type {Error} */ (e).message}\nthe page meanwhile: ${shown.join('; ')}`);
  }
}
