#!/usr/bin/env node
// The browser's path: rosbridge through the BFF's /ros relay (auth, op checks, relay), compared with the
// direct figures of bench/rosbridge_bench.py. Starts its own stack on loopback ports, stops by itself.
// 100 Hz Float64MultiArray(6) published by a rospy node; 1, 10 and 25 clients; latency = receipt - stamp.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import { WebSocket } from 'ws';
import { stackEnv, addUser, startStack, stopStack, REPO_ROOT } from '../e2e/lib/stack.js';

const QUICK = process.env.BENCH_QUICK === '1'; // npm run bench -- --quick: 1.5 s per scenario
const DURATION_S = Number(process.env.BENCH_DURATION_S || (QUICK ? 1.5 : 5));
const port = 38080;
// UR_HOST: an address no controller listens on (stackEnv's default, 127.0.0.9, is where e2e stacks run their sim).
const env = stackEnv({ port, masterPort: port + 1, rosbridgePort: port + 2, urHost: '127.0.0.27', extraEnv: { UR_SIM: '0' } });
// admin: the only role granted the bench's own topic (an operator gets what its pages use; /cell/bench was refused
// and the bench measured nothing). The op guard checks every op the same way for every role.
addUser(env, 'bench', 'admin', 'bench-password');

const PUBLISHER = `
import time, rospy
from std_msgs.msg import Float64MultiArray
rospy.init_node('bench_pub', disable_signals=True)
pub = rospy.Publisher('/cell/bench', Float64MultiArray, queue_size=10)
rate = rospy.Rate(100)
while not rospy.is_shutdown():
    pub.publish(Float64MultiArray(data=[time.time(), 1, 2, 3, 4, 5]))
    rate.sleep()
`;

const pct = (xs, p) => { const s = [...xs].sort((a, b) => a - b); return s.length ? s[Math.min(s.length - 1, Math.floor((p / 100) * s.length))] : NaN; };
const cpuTicks = (pid) => { try { const f = fs.readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' '); return Number(f[11]) + Number(f[12]); } catch { return 0; } };
const rssMb = (pid) => { try { return Number(/VmRSS:\s+(\d+)/.exec(fs.readFileSync(`/proc/${pid}/status`, 'utf8'))[1]) / 1024; } catch { return 0; } };

async function scenario(cookie, bffPid, nClients) {
  const lat = [];
  let received = 0;
  const clients = await Promise.all(Array.from({ length: nClients }, () => new Promise((resolve, reject) => {
    const ws = new WebSocket(`ws://127.0.0.1:${port}/ros`, { headers: { cookie } });
    ws.on('open', () => { ws.send(JSON.stringify({ op: 'subscribe', id: 'b', topic: '/cell/bench', type: 'std_msgs/Float64MultiArray' })); resolve(ws); });
    ws.on('error', reject);
  })));
  await new Promise((r) => setTimeout(r, 1000)); // subscriptions settle before measuring
  let measuring = true;
  for (const ws of clients) ws.on('message', (d) => {
    if (!measuring) return;
    const m = JSON.parse(d.toString());
    if (m.op === 'publish') { received++; lat.push(Date.now() - m.msg.data[0] * 1000); }
  });
  const t0 = cpuTicks(bffPid);
  await new Promise((r) => setTimeout(r, DURATION_S * 1000));
  measuring = false;
  const cpu = ((cpuTicks(bffPid) - t0) / 100 / DURATION_S) * 100;
  const rss = rssMb(bffPid);
  for (const ws of clients) ws.close();
  return { nClients, perClient: received / nClients / DURATION_S, p50: pct(lat, 50), p95: pct(lat, 95), cpu, rss };
}

const stack = await startStack(env);
const pub = spawn('bash', ['-c', `source scripts/ros-env.sh && exec python -c "${PUBLISHER.replace(/"/g, '\\"')}"`], { cwd: REPO_ROOT, env, stdio: 'ignore' });
try {
  const login = await fetch(`http://127.0.0.1:${port}/api/auth/login`, { method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ username: 'bench', password: 'bench-password' }) });
  const cookie = login.headers.get('set-cookie').split(';')[0];
  const bffPid = Number(fs.readdirSync('/proc').find((d) => /^\d+$/.test(d) && (() => { try { return fs.readFileSync(`/proc/${d}/cmdline`, 'utf8').includes('bff/src/server.js') && fs.readFileSync(`/proc/${d}/environ`, 'utf8').includes(env.DATA_DIR); } catch { return false; } })()));
  console.log(`BFF relay path, 100 Hz Float64MultiArray(6), JSON, ${DURATION_S} s per scenario${QUICK ? ' (quick)' : ''} (latency includes rosbridge)`);
  console.log('clients | msgs/s/client | p50 ms | p95 ms | BFF CPU % | BFF RSS MB');
  for (const n of [1, 10, 25]) {
    const r = await scenario(cookie, bffPid, n);
    console.log(`${String(r.nClients).padStart(7)} | ${r.perClient.toFixed(1).padStart(13)} | ${r.p50.toFixed(2).padStart(6)} | ${r.p95.toFixed(2).padStart(6)} | ${r.cpu.toFixed(1).padStart(9)} | ${r.rss.toFixed(0).padStart(10)}`);
  }
} finally {
  pub.kill('SIGINT');
  await stopStack(stack.proc);
}
