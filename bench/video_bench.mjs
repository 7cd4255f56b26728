#!/usr/bin/env node
// Raw camera to phones (docs/performance.md, "Cameras"). The demo cell's raw stream (/cell/camera/global/image_raw)
// is fed by this bench's own camera driver at 1280x720 rgb8, 30 Hz, a moving picture (the sim is not started: it
// renders about 8 frames a second without a GPU). Five phone viewers (390 css px at DPR 3: 1170 device px wide)
// connect to the BFF's /ros on loopback as the app does: /cell/video/request, then the JPEG topic it names, in CBOR,
// queue_length 1. Then the reference: the same picture as the publisher's own full-size JPEG (quality 80,
// sensor_msgs/CompressedImage, encoded by the bench's driver as a camera driver would) to five viewers directly.
// Figures per case: frames per second and age p95 per viewer (arrival - the camera's header stamp, one clock),
// bytes per frame, CPU (% of one core) of the video node, the BFF and rosbridge over the measured span.
// Starts its own stack on loopback ports, stops by itself. BENCH_QUICK=1: 5 s per case instead of 20.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import { WebSocket } from 'ws';
import { decode as cborDecode } from 'cbor-x';
import { stackEnv, addUser, startStack, stopStack, pidsOfStack, REPO_ROOT } from '../e2e/lib/stack.js';
import { procName, pct, cpuTicks, loginCookie } from './soak_cell.mjs';

const QUICK = process.env.BENCH_QUICK === '1';
const SECONDS = Number(process.env.BENCH_DURATION_S || (QUICK ? 5 : 20));
const VIEWERS = 5;
const WIDTH = 390 * 3;
const RAW = '/cell/camera/global/image_raw';
const JPEG = '/cell/camera/global/image/compressed';
const port = 38580;
const env = stackEnv({ port, masterPort: port + 1, rosbridgePort: port + 2, urHost: '127.0.0.29', extraEnv: { UR_SIM: '0' } });
addUser(env, 'bench', 'operator', 'bench-password');
const base = `http://127.0.0.1:${port}`;
const sleep = (/** @type {number} */ ms) => new Promise((r) => setTimeout(r, ms));

const DRIVER = `
import io, sys, time
import numpy as np
import rospy
from PIL import Image as PILImage
from sensor_msgs.msg import CompressedImage, Image
rospy.init_node('video_bench_camera', disable_signals=True)
raw = rospy.Publisher('${RAW}', Image, queue_size=1)
jpeg = rospy.Publisher('${JPEG}', CompressedImage, queue_size=1)
h, w = 720, 1280
y, x = np.mgrid[0:h, 0:w]
base = np.stack([(x // 4) % 256, (y // 3) % 256, ((x + y) // 6) % 256], -1).astype(np.uint8)
rate = rospy.Rate(30)
n = 0
print('ready', flush=True)
while not rospy.is_shutdown():
    px = np.roll(base, n * 8, axis=1)
    stamp = rospy.Time.now()
    if raw.get_num_connections():
        m = Image(width=w, height=h, encoding='rgb8', step=w * 3, data=px.tobytes())
        m.header.stamp, m.header.frame_id = stamp, 'camera_global'
        raw.publish(m)
    if jpeg.get_num_connections():
        b = io.BytesIO()
        PILImage.fromarray(px).save(b, format='JPEG', quality=80)
        c = CompressedImage(format='jpeg', data=b.getvalue())
        c.header.stamp, c.header.frame_id = stamp, 'camera_global'
        jpeg.publish(c)
    n += 1
    rate.sleep()
`;

/** A JPEG's width x height from its SOF marker. @param {Uint8Array} b */
function jpegSize(b) {
  for (let i = 2; i + 9 < b.length;) {
    if (b[i] !== 0xff) return '?';
    const marker = b[i + 1];
    if (marker >= 0xc0 && marker <= 0xc3) return `${(b[i + 7] << 8) | b[i + 8]}x${(b[i + 5] << 8) | b[i + 6]}`;
    i += 2 + ((b[i + 2] << 8) | b[i + 3]);
  }
  return '?';
}

/** One viewer: asks for its size (raw) or subscribes the JPEG topic, and records each frame's age and size. */
async function viewer(cookie, raw) {
  const ws = new WebSocket(`${base.replace('http', 'ws')}/ros`, { headers: { cookie } });
  await new Promise((res, rej) => { ws.once('open', res); ws.once('error', rej); });
  /** @type {{at: number, age: number, bytes: number, size: string}[]} */
  const frames = [];
  let asked = null;
  ws.on('message', (d, binary) => {
    const m = binary ? cborDecode(/** @type {Buffer} */ (d)) : JSON.parse(d.toString());
    if (m.op === 'service_response' && m.id === 'ask') asked = m.values;
    if (m.op === 'publish' && m.msg?.header) {
      const t = Date.now();
      const s = m.msg.header.stamp;
      frames.push({ at: t, age: t - (s.secs * 1000 + s.nsecs / 1e6), bytes: m.msg.data.length, size: jpegSize(m.msg.data) });
    }
  });
  let topic = JPEG;
  if (raw) {
    ws.send(JSON.stringify({ op: 'call_service', id: 'ask', service: '/cell/video/request', args: { topic: RAW, width: WIDTH, quality: 70 } }));
    const end = Date.now() + 10_000;
    while (!asked && Date.now() < end) await sleep(20);
    if (!asked?.ok) throw new Error(`/cell/video/request: ${JSON.stringify(asked)}`);
    topic = asked.topic;
  }
  ws.send(JSON.stringify({ op: 'subscribe', id: 'cam', topic, type: 'sensor_msgs/CompressedImage', queue_length: 1, compression: 'cbor' }));
  return { ws, frames, topic, asked };
}

async function measure(label, raw, cookie) {
  const vs = [];
  for (let i = 0; i < VIEWERS; i++) vs.push(await viewer(cookie, raw));
  const end0 = Date.now() + 20_000;
  while (vs.some((v) => v.frames.length < 10) && Date.now() < end0) await sleep(50);   // warm up: frames flowing
  await sleep(1000);
  const pids = new Map(pidsOfStack(env.DATA_DIR).map((p) => [p, procName(p)]));
  const t0 = Date.now();
  const ticks0 = new Map([...pids.keys()].map((p) => [p, cpuTicks(p)]));
  await sleep(SECONDS * 1000);
  const t1 = Date.now();
  /** @type {Record<string, number>} */
  const cpu = {};
  for (const [p, name] of pids) {
    const d = cpuTicks(p) - /** @type {number} */ (ticks0.get(p));
    if (Number.isFinite(d) && name) cpu[name] = (cpu[name] || 0) + (d / 100 / ((t1 - t0) / 1000)) * 100;
  }
  const rows = vs.map((v) => v.frames.filter((f) => f.at >= t0 && f.at < t1));
  const all = rows.flat();
  console.log(`\n${label}: frames of ${[...new Set(all.map((f) => f.size))].join(', ')} px${raw ? ` (asked ${WIDTH} px wide, on ${vs[0].topic})` : ''}`);
  console.log(`  per viewer: ${rows.map((r) => `${(r.length / SECONDS).toFixed(1)} fps / age p95 ${pct(r.map((f) => f.age), 95).toFixed(0)} ms`).join(', ')}`);
  console.log(`  all viewers: age p50 ${pct(all.map((f) => f.age), 50).toFixed(0)} ms, p95 ${pct(all.map((f) => f.age), 95).toFixed(0)} ms; ${(all.reduce((a, f) => a + f.bytes, 0) / Math.max(1, all.length) / 1024).toFixed(1)} KiB per frame; ${(all.reduce((a, f) => a + f.bytes, 0) / SECONDS / 1024 / 1024).toFixed(2)} MiB/s to the ${VIEWERS} viewers`);
  const show = ['video', 'bff', 'rosbridge_websocket'];
  console.log(`  CPU % of one core: ${show.map((n) => `${n} ${(cpu[n] ?? 0).toFixed(0)}`).join(', ')} (the camera driver's own encoding not counted)`);
  for (const v of vs) v.ws.close();
  await sleep(3000);   // the video node leaves the camera; the next case starts clean
}

const stack = await startStack(env);
let driver;
try {
  driver = spawn('python', ['-c', DRIVER], { cwd: REPO_ROOT, env, stdio: ['ignore', 'pipe', 'inherit'] });
  await new Promise((res, rej) => { driver.stdout.once('data', res); driver.once('exit', (c) => rej(new Error(`camera driver exited ${c}`))); });
  console.log(`Raw 1280x720 rgb8 at 30 Hz to ${VIEWERS} phone viewers (${WIDTH} device px) through the BFF on loopback, ${SECONDS} s per case`);
  const cookie = await loginCookie(base, 'bench', 'bench-password');
  await measure('raw stream through the video node, JPEG sized to the phone', true, cookie);
  await measure('reference: the publisher\'s full-size JPEG (quality 80) to each viewer', false, cookie);
} finally {
  driver?.kill('SIGTERM');
  await stopStack(stack.proc);
}
