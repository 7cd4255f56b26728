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
