#!/usr/bin/env node
// ROS log storm: a rospy node logs at 1 kHz for 60 s (rospy.loginfo: /rosout, aggregated by rosout into
// /rosout_agg) while an admin's tablet shows the Inspect page's Log tab (live /rosout_agg through the BFF). Measured
// every 5 s: the RSS (and its private part) of the BFF, the inspect node (its history bounded by the cell file's
// inspect.log_keep_entries), rosout and rosbridge; in the page: animation frames per second, the longest frame, and
// how long a click on "Minimum level" takes to show its result (the page stays usable). Target: RSS flat (the
// history and the page's list are bounded), the page responsive. Starts its own stack (no sim), stops by itself.
import fs from 'node:fs';
import { spawn } from 'node:child_process';
import { chromium, devices } from '@playwright/test';
import { stackEnv, addUser, startStack, stopStack, pidsOfStack, REPO_ROOT } from '../e2e/lib/stack.js';
import { procName } from './soak_cell.mjs';

const QUICK = process.env.BENCH_QUICK === '1';
const SECONDS = Number(process.env.BENCH_DURATION_S || (QUICK ? 15 : 60));
const RATE = 1000;
const port = 38580;
const env = stackEnv({ port, masterPort: port + 1, rosbridgePort: port + 2, urHost: '127.0.0.29', extraEnv: { UR_SIM: '0' } });
addUser(env, 'bench', 'admin', 'bench-password');

// Logs in bursts of 10 every 10 ms (1 kHz): rospy.Rate at 1 kHz would lose time to its own sleeps.
const STORM = `
import sys, time, rospy
rospy.init_node('log_storm', disable_signals=True)
rate, seconds = ${RATE}, ${SECONDS}
t0 = time.monotonic(); n = 0
while time.monotonic() - t0 < seconds and not rospy.is_shutdown():
    due = int((time.monotonic() - t0) * rate)
    while n < due:
        rospy.loginfo('storm %d: the gripper reports pressure %.2f bar on cycle %d', n, 5 + (n % 7) / 10.0, n // 100)
        n += 1
    time.sleep(0.01)
print('logged %d in %.1f s' % (n, time.monotonic() - t0), flush=True)
`;

const memMiB = (pid) => {
  try {
    const st = fs.readFileSync(`/proc/${pid}/status`, 'utf8');
    return [Number(/VmRSS:\s+(\d+)/.exec(st)[1]) / 1024, Number(/RssAnon:\s+(\d+)/.exec(st)[1]) / 1024];
  } catch { return [NaN, NaN]; }
};
const WATCH = ['bff', 'inspect', 'rosout', 'rosbridge'];
const pidsByName = () => {
  const out = new Map();
  for (const pid of pidsOfStack(env.DATA_DIR)) {
    const name = procName(pid);
    const key = WATCH.find((w) => name === w || name === `/${w}` || (w === 'rosbridge' && /rosbridge/.test(name || '')));
    if (key && !out.has(key)) out.set(key, pid);
  }
  return out;
};

const stack = await startStack(env);
const browser = await chromium.launch({ executablePath: process.env.CHROMIUM_PATH || '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'] });
let storm = null;
try {
  const context = await browser.newContext({ ...devices['Galaxy Tab S4'], baseURL: `http://localhost:${port}` });
  const page = await context.newPage();
  await page.goto('/login');
  await page.getByTestId('login-username').fill('bench');
  await page.getByTestId('login-password').fill('bench-password');
  await page.getByTestId('login-submit').click();
  await page.waitForURL((u) => !u.pathname.startsWith('/login'));
  await page.goto('/inspect');
  await page.getByRole('list', { name: 'ROS log' }).waitFor({ timeout: 30_000 });
  const pids = pidsByName();
  console.log(`ROS log storm: ${RATE} entries/s for ${SECONDS} s${QUICK ? ' (quick)' : ''}; the Inspect page's Log tab open on a tablet (Galaxy Tab S4 profile); pids ${[...pids].map(([k, v]) => `${k} ${v}`).join(', ')}`);
  const before = new Map([...pids].map(([k, p]) => [k, memMiB(p)]));
  console.log(`  before: ${[...before].map(([k, [r, a]]) => `${k} ${r.toFixed(1)} (${a.toFixed(1)} anon)`).join(', ')} MiB`);

  let stormOut = '';
  storm = spawn('bash', ['-c', `source scripts/ros-env.sh && exec python -c "${STORM.replace(/"/g, '\\"')}"`], { cwd: REPO_ROOT, env, stdio: ['ignore', 'pipe', 'ignore'] });
  storm.stdout.on('data', (d) => { stormOut += d; });
  const stormDone = new Promise((r) => storm.once('exit', r));
  const level = page.getByLabel('Minimum level');
  console.log('    t s | RSS MiB (anon): bff | inspect | rosout | rosbridge | page fps | longest frame ms | filter click -> shown ms');
  const rows = [];
  const t0 = Date.now();
  let flip = false;
  while (Date.now() - t0 < (SECONDS + 5) * 1000) {
    // 5 s of frames in the page, then a filter click timed to its result (the list's first entry's level).
    const frames = await page.evaluate(() => new Promise((resolve) => {
      const times = [];
      const start = performance.now();
      const tick = (t) => { times.push(t); if (t - start < 4500) requestAnimationFrame(tick); else resolve(times); };
      requestAnimationFrame(tick);
    }));
    const gaps = frames.slice(1).map((t, i) => t - frames[i]);
    flip = !flip;
    const c0 = Date.now();
    await level.selectOption(flip ? 'warn' : 'debug');
    await page.waitForFunction((want) => {
      const first = document.querySelector('[data-testid="log-entry"]');
      return want === 'warn' ? !first || first.getAttribute('data-level') !== 'info' : first?.getAttribute('data-level') === 'info';
    }, flip ? 'warn' : 'debug', { timeout: 30_000 }).catch(() => null);
    const click = Date.now() - c0;
    const mem = new Map([...pids].map(([k, p]) => [k, memMiB(p)]));
    const t = (Date.now() - t0) / 1000;
    rows.push({ t, mem, fps: (frames.length - 1) / ((frames.at(-1) - frames[0]) / 1000), longest: Math.max(...gaps), click });
    const r = rows.at(-1);
    console.log(`  ${t.toFixed(0).padStart(5)} | ${WATCH.map((k) => { const [m, a] = mem.get(k) ?? [NaN, NaN]; return `${m.toFixed(1)} (${a.toFixed(1)})`; }).join(' | ')} | ${r.fps.toFixed(1).padStart(8)} | ${r.longest.toFixed(0).padStart(16)} | ${String(click).padStart(6)}`);
  }
  await stormDone;
  console.log(`  storm: ${stormOut.split('\n').find((l) => l.startsWith('logged')) ?? 'no summary'}`);
  const during = rows.filter((r) => r.t > 10 && r.t <= SECONDS);
  for (const k of WATCH) {
    const first = during[0]?.mem.get(k)?.[0]; const last = during.at(-1)?.mem.get(k)?.[0];
    const peak = Math.max(...during.map((r) => r.mem.get(k)?.[0] ?? NaN));
    console.log(`  ${k}: RSS ${before.get(k)?.[0].toFixed(1)} before -> ${first?.toFixed(1)} at ${during[0]?.t.toFixed(0)} s -> ${last?.toFixed(1)} at ${during.at(-1)?.t.toFixed(0)} s (peak ${peak.toFixed(1)}) MiB`);
  }
  const fps = during.map((r) => r.fps);
  console.log(`  page: ${Math.min(...fps).toFixed(1)}-${Math.max(...fps).toFixed(1)} fps, longest frame ${Math.max(...during.map((r) => r.longest)).toFixed(0)} ms, filter click to result ${Math.max(...during.map((r) => r.click))} ms at most`);
  console.log('  target: RSS flat during the storm (bounded history and list); the page keeps drawing and answers a click within 1 s');
} finally {
  storm?.kill('SIGINT');
  await browser.close();
  await stopStack(stack.proc);
}
