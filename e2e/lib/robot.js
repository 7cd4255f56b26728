// Watching the arm from outside the app, as an engineer would with `rostopic echo`: a plain rosbridge client
// on the stack's own rosbridge port (loopback, behind the BFF), subscribed to the driver's /joint_states.
import { WebSocket } from 'ws';

/**
 * @typedef {object} RobotWatch
 * @property {() => number[]} joints  the latest actual joint positions (rad)
 * @property {() => number} speed  the largest absolute joint velocity in the latest message (rad/s)
 * @property {(n: number) => Promise<{maxSpeed: number, travel: number}>} observe  the next n messages
 * @property {() => void} close
 */

/** @param {string} url e.g. ws://127.0.0.1:18082 @returns {Promise<RobotWatch>} */
export async function watchRobot(url = process.env.E2E_ROSBRIDGE_URL || '') {
  const ws = new WebSocket(url);
  /** @type {{position: number[], velocity: number[]} | null} */
  let last = null;
  /** @type {Array<(m: {position: number[], velocity: number[]}) => void>} */
  let listeners = [];
  ws.on('message', (d) => {
    const m = JSON.parse(d.toString());
    if (m.op !== 'publish' || m.topic !== '/joint_states') return;
    last = m.msg;
    for (const l of listeners) l(m.msg);
  });
  await new Promise((resolve, reject) => { ws.once('open', resolve); ws.once('error', reject); });
  ws.send(JSON.stringify({ op: 'subscribe', id: 'e2e-joints', topic: '/joint_states', type: 'sensor_msgs/JointState' }));
  const first = Date.now();
  while (!last) {
    if (Date.now() - first > 20_000) throw new Error('no /joint_states from the robot driver within 20 s');
    await new Promise((r) => setTimeout(r, 20));
  }
  const now = () => /** @type {{position: number[], velocity: number[]}} */ (last);
  return {
    joints: () => [...now().position],
    speed: () => Math.max(...now().velocity.map(Math.abs)),
    observe: (n) => new Promise((resolve) => {
      const start = [...now().position];
      let maxSpeed = 0;
      let seen = 0;
      /** @param {{position: number[], velocity: number[]}} m */
      const l = (m) => {
        maxSpeed = Math.max(maxSpeed, ...m.velocity.map(Math.abs));
        if (++seen < n) return;
        listeners = listeners.filter((x) => x !== l);
        resolve({ maxSpeed, travel: Math.max(...m.position.map((q, i) => Math.abs(q - start[i]))) });
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

/** The driver's state (20 Hz, /cell/manual/state), kept as TCP samples. @param {string} url @returns {Promise<TcpWatch>} */
export async function watchTcp(url = process.env.E2E_ROSBRIDGE_URL || '') {
  const ws = new WebSocket(url);
  /** @type {{ at: number, p: number[] }[]} */
  const samples = [];
  ws.on('message', (d) => {
    const m = JSON.parse(d.toString());
    if (m.op !== 'publish' || m.topic !== '/cell/manual/state' || !Array.isArray(m.msg?.tcp_pose) || m.msg.tcp_pose.length < 6) return;
    samples.push({ at: Date.now(), p: m.msg.tcp_pose });
    if (samples.length > 20_000) samples.splice(0, 10_000);
  });
  await new Promise((resolve, reject) => { ws.once('open', resolve); ws.once('error', reject); });
  ws.send(JSON.stringify({ op: 'subscribe', id: 'e2e-tcp', topic: '/cell/manual/state', type: 'cell_msgs/RobotState' }));
  const first = Date.now();
  while (!samples.length) {
    if (Date.now() - first > 20_000) throw new Error('no /cell/manual/state from the robot driver within 20 s');
    await new Promise((r) => setTimeout(r, 20));
  }
  return {
    pose: () => [...samples[samples.length - 1].p],
    closest: (target, sinceMs = 0) => Math.min(...samples.filter((s) => s.at >= sinceMs)
      .map((s) => Math.hypot(s.p[0] - target[0], s.p[1] - target[1], s.p[2] - target[2]))),
    close: () => ws.close(),
  };
}
