#!/usr/bin/env node
// Sensors page smoothness on a phone profile (Chromium, Pixel 7) with six 100 Hz series: a rospy publisher sends
// geometry_msgs/WrenchStamped at 100 Hz on the cell file's wrench topic (/cell/wrench; the simulated cell is not
// started, so it is the only publisher), the page draws it through the BFF and rosbridge. Measured in the page:
// animation frames per second (requestAnimationFrame), frame-time p95 and long frames, chart draws per second,
// and the messages per second the page receives (rosbridge throttles per the page's choice), with the CPU
// unthrottled and throttled 4x (DevTools Emulation.setCPUThrottlingRate), and at 4x with the graph paused (the
// page's own baseline). Target: >= 50 fps at 4x. PROFILE=1 adds the top functions of a 5 s CPU profile at 4x.
// Starts its own stack on loopback ports, stops by itself.
import { spawn } from 'node:child_process';
import { chromium, devices } from '@playwright/test';
import { stackEnv, addUser, startStack, stopStack, REPO_ROOT } from '../e2e/lib/stack.js';

const QUICK = process.env.BENCH_QUICK === '1'; // npm run bench -- --quick: 3 s per run (the window still fills first)
const SECONDS = Number(process.env.BENCH_DURATION_S || (QUICK ? 3 : 10));
const port = 38480;
// UR_HOST: an address no controller listens on (stackEnv's default, 127.0.0.9, is where e2e stacks run their sim).
const env = stackEnv({ port, masterPort: port + 1, rosbridgePort: port + 2, urHost: '127.0.0.28', extraEnv: { UR_SIM: '0' } });
addUser(env, 'bench', 'operator', 'bench-password');

const PUBLISHER = `
import math, time, rospy
from geometry_msgs.msg import WrenchStamped
rospy.init_node('sensors_bench_pub', disable_signals=True)
pub = rospy.Publisher('/cell/wrench', WrenchStamped, queue_size=10)
rate = rospy.Rate(100)
i = 0
while not rospy.is_shutdown():
    t = time.time()
    m = WrenchStamped()
    m.header.stamp = rospy.Time.now()
    m.header.frame_id = 'ft_sensor'
    f = [20 * math.sin(t * (k + 1)) + (45 if i % 250 == 0 and k == 2 else 0) for k in range(6)]
    m.wrench.force.x, m.wrench.force.y, m.wrench.force.z = f[0], f[1], f[2]
    m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z = f[3] / 10, f[4] / 10, f[5] / 10
    pub.publish(m)
    i += 1
    rate.sleep()
`;

const stack = await startStack(env);
const pub = spawn('bash', ['-c', `source scripts/ros-env.sh && exec python -c "${PUBLISHER.replace(/"/g, '\\"')}"`], { cwd: REPO_ROOT, env, stdio: 'ignore' });
const browser = await chromium.launch({ executablePath: process.env.CHROMIUM_PATH || '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'] });
try {
  const context = await browser.newContext({ ...devices['Pixel 7'], baseURL: `http://localhost:${port}` });
  const page = await context.newPage();
  let throttle = null;
  let wrenchFrames = 0;
  page.on('websocket', (ws) => {
    ws.on('framesent', (f) => {
      if (typeof f.payload === 'string' && f.payload.includes('"/cell/wrench"') && f.payload.includes('"subscribe"')) throttle = JSON.parse(f.payload).throttle_rate;
    });
    ws.on('framereceived', (f) => { if (typeof f.payload !== 'string' && f.payload.includes('/cell/wrench')) wrenchFrames++; });
  });
  await page.goto('/login');
  await page.getByTestId('login-username').fill('bench');
  await page.getByTestId('login-password').fill('bench-password');
  await page.getByTestId('login-submit').click();
  await page.waitForURL((u) => !u.pathname.startsWith('/login'));
  await page.goto('/sensors');
  const plot = page.getByTestId('sensor-graph').filter({ hasText: 'Wrist wrench' }).getByTestId('sensor-plot');
  await plot.and(page.locator('[data-draws]')).waitFor({ timeout: 30_000 });
  await page.waitForTimeout(11_000); // the 10 s window fills: every frame draws a full window
  const cdp = await context.newCDPSession(page);
  const plotWidth = await plot.evaluate((el) => el.clientWidth);

  /** Frame statistics over SECONDS in the page. */
  const measure = async () => {
    const draws0 = Number(await plot.getAttribute('data-draws'));
    const msgs0 = wrenchFrames;
    const r = await page.evaluate((seconds) => new Promise((resolve) => {
      const times = [];
      const t0 = performance.now();
      const tick = (t) => {
        times.push(t);
        if (t - t0 < seconds * 1000) requestAnimationFrame(tick);
        else resolve(times);
      };
      requestAnimationFrame(tick);
    }), SECONDS);
    const draws = Number(await plot.getAttribute('data-draws')) - draws0;
    const drawMs = Number(await plot.getAttribute('data-draw-ms'));
    const msgs = wrenchFrames - msgs0;
    const dts = r.slice(1).map((t, i) => t - r[i]).sort((a, b) => a - b);
    const span = (r.at(-1) - r[0]) / 1000;
    return {
      fps: (r.length - 1) / span,
      p95: dts[Math.floor(dts.length * 0.95)],
      max: dts.at(-1),
      long: dts.filter((d) => d > 50).length,
      drawsPerS: draws / span,
      msgsPerS: msgs / span,
      drawMs,
    };
  };
  console.log(`Sensors page, phone profile (Pixel 7), one time-series of 6 fields published at 100 Hz, ${SECONDS} s per run${QUICK ? ' (quick)' : ''}`);
  console.log(`  plot ${plotWidth} CSS px wide, 10 s window; the page asked rosbridge for throttle_rate ${throttle} ms`);
  console.log('  CPU         | fps  | frame p95 ms | frame max ms | frames > 50 ms | chart draws/s | draw ms (decimate + update) | msgs/s received');
  const pause = page.getByRole('button', { name: /^(Pause|Resume) Wrist wrench$/ });
  for (const [rate, paused] of [[1, false], [4, false], [4, true]]) {
    if (paused) await pause.click(); // the baseline: the same page with the graph paused (nothing drawn)
    await cdp.send('Emulation.setCPUThrottlingRate', { rate });
    await page.waitForTimeout(1000);
    const m = await measure();
    console.log(`  ${`${rate}x${paused ? ', paused' : ''}`.padEnd(11)} | ${m.fps.toFixed(1).padStart(4)} | ${m.p95.toFixed(1).padStart(12)} | ${m.max.toFixed(1).padStart(12)} | ${String(m.long).padStart(14)} | ${m.drawsPerS.toFixed(1).padStart(13)} | ${(m.drawsPerS > 0 ? m.drawMs.toFixed(2) : '—').padStart(27)} | ${m.msgsPerS.toFixed(1).padStart(15)}`);
  }
  if (process.env.PROFILE) {
    await pause.click(); // drawing again
    await cdp.send('Emulation.setCPUThrottlingRate', { rate: 4 });
    await cdp.send('Profiler.enable');
    await cdp.send('Profiler.setSamplingInterval', { interval: 200 });
    await cdp.send('Profiler.start');
    await page.waitForTimeout(5000);
    const { profile } = await cdp.send('Profiler.stop');
    const self = new Map();
    const byId = new Map(profile.nodes.map((n) => [n.id, n]));
    const dt = profile.timeDeltas;
    profile.samples.forEach((id, i) => { const n = byId.get(id); const k = `${n.callFrame.functionName || '(anon)'} ${n.callFrame.url.split('/').pop()}:${n.callFrame.lineNumber}`; self.set(k, (self.get(k) || 0) + (dt[i] || 0)); });
    const total = [...self.values()].reduce((a, b) => a + b, 0);
    for (const [k, v] of [...self.entries()].sort((a, b) => b[1] - a[1]).slice(0, 25)) console.log(`   ${(v / 1000).toFixed(0).padStart(6)} ms ${(100 * v / total).toFixed(1).padStart(5)} %  ${k}`);
  }
  await cdp.send('Emulation.setCPUThrottlingRate', { rate: 1 });
  console.log('  target: >= 50 fps with the CPU throttled 4x');
} finally {
  await browser.close();
  pub.kill('SIGINT');
  await stopStack(stack.proc);
}
