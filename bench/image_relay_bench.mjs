#!/usr/bin/env node
// The relay's CPU per image frame (docs/performance.md, "Cameras"): a 640x480 JPEG CompressedImage of about 30 KB at
// 30 Hz to five viewers in CBOR (queue_length 1, as the app's camera view subscribes), in one run against
//   ref     rosbridge_suite 0.11.17's own server, directly (bench/reference/rosbridge_suite.sh; skipped when not set up)
//   ours    our rosbridge server, directly
//   phone   the phone's whole path: the BFF's /ros (auth, op rules, lanes) in front of our rosbridge
// The cases take turns (ROUNDS times), so a burst of load on the shared machine hits each alike. Figures per case:
// frames per second per viewer, age p95, and CPU time per delivered frame of the serving processes (ref: its
// server; ours: rosbridge; phone: BFF + rosbridge) above what they spend idle just before. Starts its own stack on loopback ports, stops by itself.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import { WebSocket } from 'ws';
import { decode as cborDecode } from 'cbor-x';
import { stackEnv, addUser, startStack, stopStack, pidsOfStack, REPO_ROOT } from '../e2e/lib/stack.js';
import { procName, pct, cpuTicks, loginCookie } from './soak_cell.mjs';

const QUICK = process.env.BENCH_QUICK === '1';
const SECONDS = Number(process.env.BENCH_DURATION_S || (QUICK ? 5 : 15));
const ROUNDS = Number(process.env.BENCH_ROUNDS || (QUICK ? 1 : 3));
const IDLE_S = QUICK ? 2 : 5;
const VIEWERS = 5;
const CASES = (process.env.BENCH_CASES || 'ref,ours,phone').split(',');   // e.g. BENCH_CASES=phone with a profiler
const TOPIC = '/cell/camera/global/image/compressed';
const port = 38680;
const refPort = port + 5;
const env = stackEnv({ port, masterPort: port + 1, rosbridgePort: port + 2, urHost: '127.0.0.30', extraEnv: { UR_SIM: '0', NODE_OPTIONS: process.env.BENCH_STACK_NODE_OPTIONS || '' } });
addUser(env, 'bench', 'operator', 'bench-password');
const base = `http://127.0.0.1:${port}`;
const sleep = (/** @type {number} */ ms) => new Promise((r) => setTimeout(r, ms));

const DRIVER = `
import io, time
import numpy as np
import rospy
from PIL import Image
from sensor_msgs.msg import CompressedImage
rospy.init_node('image_relay_bench_camera', disable_signals=True)
pub = rospy.Publisher('${TOPIC}', CompressedImage, queue_size=1)
rng = np.random.default_rng(1)
small = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
px = np.asarray(Image.fromarray(small).resize((640, 480), Image.BICUBIC))
for q in range(95, 5, -5):
    b = io.BytesIO(); Image.fromarray(px).save(b, format='JPEG', quality=q)
    if len(b.getvalue()) <= 30 * 1024: break
data = b.getvalue()
print('ready %d' % len(data), flush=True)
rate = rospy.Rate(30)
while not rospy.is_shutdown():
    m = CompressedImage(format='jpeg', data=data)
    m.header.stamp, m.header.frame_id = rospy.Time.now(), 'camera_global'
    pub.publish(m)
    rate.sleep()
`;

/** @param {string} url @param {Record<string, string>} headers */
async function viewer(url, headers) {
  const ws = new WebSocket(url, { headers });
  await new Promise((res, rej) => { ws.once('open', res); ws.once('error', rej); });
  /** @type {{at: number, age: number}[]} */
  const frames = [];
  ws.on('message', (d, binary) => {
    const m = binary ? cborDecode(/** @type {Buffer} */ (d)) : JSON.parse(d.toString());
    if (m.op === 'publish' && m.msg?.header) {
      const t = Date.now();
      const s = m.msg.header.stamp;
      frames.push({ at: t, age: t - (s.secs * 1000 + s.nsecs / 1e6) });
    }
  });
  ws.send(JSON.stringify({ op: 'subscribe', id: 'cam', topic: TOPIC, type: 'sensor_msgs/CompressedImage', queue_length: 1, compression: 'cbor' }));
  return { ws, frames };
}

/** @type {Record<string, {frames: number, cpuS: number, ages: number[], fps: number[]}>} */
const totals = {};

/** @param {string} label @param {string} url @param {Record<string,string>} headers @param {number[]} pids */
async function measure(label, url, headers, pids) {
  // What the serving processes spend with nobody watching (the stack's own traffic: it falls for a minute or two
  // after the stack starts), subtracted: the figure is what the image frames cost.
  const i0 = Date.now();
  const idle0 = pids.map(cpuTicks);
  await sleep(IDLE_S * 1000);
  const idleRate = pids.reduce((a, p, i) => a + (cpuTicks(p) - idle0[i]) / 100, 0) / ((Date.now() - i0) / 1000);
  const vs = [];
  for (let i = 0; i < VIEWERS; i++) vs.push(await viewer(url, headers));
  const end0 = Date.now() + 20_000;
  while (vs.some((v) => v.frames.length < 10) && Date.now() < end0) await sleep(50);
  await sleep(1000);
  const t0 = Date.now();
  const ticks0 = pids.map(cpuTicks);
  await sleep(SECONDS * 1000);
  const t1 = Date.now();
  const each = pids.map((p, i) => (cpuTicks(p) - ticks0[i]) / 100);
  const grossS = each.reduce((a, x) => a + x, 0);
  const cpuS = Math.max(0, grossS - idleRate * ((t1 - t0) / 1000));
  const rows = vs.map((v) => v.frames.filter((f) => f.at >= t0 && f.at < t1));
  const frames = rows.reduce((a, r) => a + r.length, 0);
  const ages = rows.flat().map((f) => f.age);
  const t = (totals[label] ??= { frames: 0, cpuS: 0, ages: [], fps: [] });
  t.frames += frames; t.cpuS += cpuS; t.ages.push(...ages); t.fps.push(...rows.map((r) => r.length / ((t1 - t0) / 1000)));
  console.log(`  ${label.padEnd(6)} ${(frames / VIEWERS / ((t1 - t0) / 1000)).toFixed(1)} fps each, age p95 ${pct(ages, 95).toFixed(1)} ms, CPU ${(grossS / ((t1 - t0) / 1000) * 100).toFixed(1)} % of a core (${(idleRate * 100).toFixed(1)} % idle before), ${(cpuS * 1e6 / Math.max(1, frames)).toFixed(0)} us per delivered frame above idle${pids.length > 1 ? ` (${each.map((x) => `${(x * 1e6 / Math.max(1, frames)).toFixed(0)}`).join(' + ')} us gross)` : ''}`);
  for (const v of vs) v.ws.close();
  await sleep(2000);   // the servers drop the subscriptions before the next case
}

/** rosbridge_suite's server beside our stack, or null (said why) when it is not set up or does not start. */
async function startReference() {
  const proc = spawn('bash', [`${REPO_ROOT}/bench/reference/rosbridge_suite.sh`, 'run', String(refPort)], { cwd: REPO_ROOT, env, stdio: ['ignore', 'pipe', 'pipe'] });
  let log = '';
  proc.stdout.on('data', (d) => { log += d; });
  proc.stderr.on('data', (d) => { log += d; });
  const end = Date.now() + 20_000;
  while (!/server started/.test(log) && proc.exitCode === null && Date.now() < end) await sleep(100);
  if (/server started/.test(log)) return proc;
  proc.kill('SIGTERM');
  console.log(`ref skipped: rosbridge_suite did not start (${log.trim().split('\n').pop() || 'no output'}; bash bench/reference/rosbridge_suite.sh setup)`);
  return null;
}

const stack = await startStack(env);
let driver;
/** @type {import('node:child_process').ChildProcess|null} */
let ref = null;
try {
  driver = spawn('python', ['-c', DRIVER], { cwd: REPO_ROOT, env, stdio: ['ignore', 'pipe', 'inherit'] });
  const ready = await new Promise((res, rej) => { driver.stdout.once('data', (d) => res(String(d).trim())); driver.once('exit', (c) => rej(new Error(`camera exited ${c}`))); });
  const bytes = Number(String(ready).split(' ')[1]);
  ref = CASES.includes('ref') ? await startReference() : null;
  const names = new Map(pidsOfStack(env.DATA_DIR).map((p) => [procName(p), p]));
  const rb = /** @type {number} */ (names.get('rosbridge_websocket'));
  const bff = /** @type {number} */ (names.get('bff'));
  const cookie = await loginCookie(base, 'bench', 'bench-password');
  console.log(`A ${bytes} B JPEG CompressedImage (640x480) at 30 Hz to ${VIEWERS} viewers, CBOR, queue_length 1; ${ROUNDS} round(s) of ${SECONDS} s per case`);
  const round = async () => {
    if (ref) await measure('ref', `ws://127.0.0.1:${refPort}`, {}, [/** @type {number} */ (ref.pid)]);
    if (CASES.includes('ours')) await measure('ours', `ws://127.0.0.1:${port + 2}`, {}, [rb]);
    if (CASES.includes('phone')) await measure('phone', `ws://127.0.0.1:${port}/ros`, { cookie }, [bff, rb]);
  };
  // Unmeasured first: the BFF's JIT warms up on its first frames (its first measured round was 20-35 % dearer).
  if (!QUICK) {
    console.log('warm-up (not counted)');
    await round();
    for (const k of Object.keys(totals)) delete totals[k];
  }
  for (let r = 1; r <= ROUNDS; r++) {
    console.log(`round ${r}`);
    await round();
  }
  console.log('all rounds:');
  for (const [label, t] of Object.entries(totals)) {
    const us = (t.cpuS * 1e6) / Math.max(1, t.frames);
    const vsRef = totals.ref ? ` (${(us / ((totals.ref.cpuS * 1e6) / Math.max(1, totals.ref.frames))).toFixed(2)}x ref)` : '';
    console.log(`  ${label.padEnd(6)} ${us.toFixed(0)} us CPU per delivered frame above idle${vsRef}; fps min ${Math.min(...t.fps).toFixed(1)}; age p50 ${pct(t.ages, 50).toFixed(1)} / p95 ${pct(t.ages, 95).toFixed(1)} ms`);
  }
} finally {
  ref?.kill('SIGTERM');
  driver?.kill('SIGTERM');
  await stopStack(stack.proc);
}
