#!/usr/bin/env node
// Hold-to-run jogging, measured through the real page on a phone profile (Chromium), the BFF, rosbridge, the
// driver and the simulated arm of a cell: BENCH_CELL (default config/demo-cell.yaml: ur_rtde and the simulated UR5,
// the arm's motion read as the controller's own state by ur_rtde receive at 500 Hz, bench/rtde_probe.py;
// config/iiwa-cell.yaml: the ros_control backend and the simulated iiwa driver, the motion read from that driver's
// joint states at 200 Hz, bench/joint_states_probe.py). Starts its own stack on loopback ports, stops by itself.
//   release -> decelerating (TCP speed below 95 % of the held speed), release -> standstill,
//   browser frozen mid-jog (debugger pause: no heartbeats, socket open) -> standstill, peak TCP speed at full slider.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import readline from 'node:readline';
import { chromium, devices } from '@playwright/test';
import { stackEnv, addUser, startStack, stopStack, REPO_ROOT } from '../e2e/lib/stack.js';

const QUICK = process.env.BENCH_QUICK === '1'; // npm run bench -- --quick: 3 runs each
const REPS = Number(process.env.BENCH_REPS || (QUICK ? 3 : 5));
const cellFile = path.resolve(REPO_ROOT, process.env.BENCH_CELL || 'config/demo-cell.yaml');
const cell = /** @type {any} */ (yaml.load(fs.readFileSync(cellFile, 'utf8')));
const rosControl = cell.manual.groups[0].driver === 'ros_control';
const port = rosControl ? 38280 : 38180;
const urHost = '127.0.0.12';
const env = stackEnv({ port, masterPort: port + 1, rosbridgePort: port + 2, urHost, extraEnv: { CELL_CONFIG: cellFile } });
addUser(env, 'bench', 'admin', 'bench-password');

/** @type {Array<{t: number, lin: number, qd: number}>} wall time (ms), TCP speed (m/s), max joint speed (rad/s) */
const samples = [];
const wallMs = () => performance.timeOrigin + performance.now();
const STILL = { lin: 0.002, qd: 0.002 };
const pct = (xs, p) => { const s = [...xs].sort((a, b) => a - b); return s[Math.min(s.length - 1, Math.floor((p / 100) * s.length))]; };
const fmt = (xs) => `median ${pct(xs, 50).toFixed(0)} ms, max ${Math.max(...xs).toFixed(0)} ms (n=${xs.length})`;

/** @param {(s: {t: number, lin: number, qd: number}) => boolean} pred @param {number} from wall ms */
async function firstSample(pred, from, timeoutMs = 3000) {
  const end = Date.now() + timeoutMs;
  for (;;) {
    const s = samples.find((x) => x.t >= from && pred(x));
    if (s) return s;
    if (Date.now() > end) throw new Error('condition not reached in the controller state');
    await new Promise((r) => setTimeout(r, 20));
  }
}

const stack = await startStack(env);
const probeCmd = rosControl ? `python bench/joint_states_probe.py ${cellFile}` : `python bench/rtde_probe.py ${urHost}`;
const probe = spawn('bash', ['-c', `source scripts/ros-env.sh && exec ${probeCmd}`], { cwd: REPO_ROOT, env, stdio: ['ignore', 'pipe', 'inherit'] });
readline.createInterface({ input: probe.stdout }).on('line', (l) => {
  const [t, lin, qd] = l.split(' ').map(Number);
  samples.push({ t: t * 1000, lin, qd });
  if (samples.length > 60_000) samples.splice(0, 30_000);
});
const browser = await chromium.launch({ executablePath: process.env.CHROMIUM_PATH || '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'] });
try {
  const context = await browser.newContext({ ...devices['Pixel 7'], baseURL: `http://localhost:${port}` });
  const page = await context.newPage();
  await page.goto('/login');
  await page.getByTestId('login-username').fill('bench');
  await page.getByTestId('login-password').fill('bench-password');
  await page.getByTestId('login-submit').click();
  await page.waitForURL((u) => !u.pathname.startsWith('/login'));
  await page.goto('/manual');
  await page.getByRole('button', { name: 'Take control' }).click();
  await page.getByTestId('lease-holder').filter({ hasText: 'You have control' }).waitFor();
  // The driver's groups and limits come by a service call: until they are in, a jog button does nothing, and their
  // arrival sets the speed slider to the driver's default. On a loaded machine they can come after the slider is set.
  await page.getByTestId('manual-setup').waitFor({ state: 'detached', timeout: 30_000 });
  await page.getByTestId('manual-gate').filter({ hasText: 'Motion controls ready' }).waitFor({ timeout: 30_000 });
  await firstSample(() => true, 0, 20_000);

  /** Set a range input to its maximum the way a keyboard user would (End), so the page's own input handler runs. */
  const sliderToMax = async (name) => {
    const slider = page.getByRole('slider', { name });
    await slider.focus();
    await slider.press('End');
    await page.getByTestId('jog-speed-value').filter({ hasText: '100 %' }).waitFor();
  };
  /** Press and hold a jog button for holdMs; returns the wall time of the press. */
  const hold = async (name, holdMs) => {
    const btn = page.getByRole('button', { name, exact: true });
    await btn.waitFor();
    await btn.hover();
    await firstSample((s) => s.lin < STILL.lin && s.qd < STILL.qd, wallMs());
    const t0 = wallMs();
    await page.mouse.down();
    await firstSample((s) => s.qd > 0.01, t0);
    await new Promise((r) => setTimeout(r, holdMs));
    return t0;
  };

  const decel = [], still = [], jointStill = [], frozen = [];
  let peak = 0;
  await page.getByRole('radio', { name: 'Cartesian jog' }).check();
  await sliderToMax('Jog speed');
  for (let i = 0; i < REPS; i++) {
    const pressed = await hold(i % 2 ? 'Jog Z -' : 'Jog Z +', 1000);
    const held = samples.filter((s) => s.t > wallMs() - 200).map((s) => s.lin);
    const speed = pct(held, 50);
    const tRelease = wallMs();
    await page.mouse.up();
    const window = samples.filter((s) => s.t >= pressed && s.t <= tRelease);
    const top = window.reduce((a, b) => (b.lin > a.lin ? b : a), window[0]);
    if (process.env.BENCH_DEBUG) console.log(`  run ${i}: held ${(speed * 1000).toFixed(1)} mm/s, peak ${(top.lin * 1000).toFixed(1)} mm/s at ${(top.t - pressed).toFixed(0)} ms after the press`);
    peak = Math.max(peak, top.lin);
    decel.push((await firstSample((s) => s.lin < 0.95 * speed, tRelease)).t - tRelease);
    still.push((await firstSample((s) => s.lin < STILL.lin && s.qd < STILL.qd, tRelease)).t - tRelease);
  }
  await page.getByRole('radio', { name: 'Joint jog' }).check();
  for (let i = 0; i < REPS; i++) {
    await hold(i % 2 ? 'Jog joint 1 -' : 'Jog joint 1 +', 600);
    const tRelease = wallMs();
    await page.mouse.up();
    jointStill.push((await firstSample((s) => s.qd < STILL.qd, tRelease)).t - tRelease);
  }
  await page.getByRole('radio', { name: 'Cartesian jog' }).check();
  const cdp = await context.newCDPSession(page);
  await cdp.send('Debugger.enable');
  for (let i = 0; i < REPS; i++) {
    await hold(i % 2 ? 'Jog Y -' : 'Jog Y +', 600);
    const tFreeze = wallMs();
    await cdp.send('Debugger.pause');
    frozen.push((await firstSample((s) => s.lin < STILL.lin && s.qd < STILL.qd, tFreeze)).t - tFreeze);
    await cdp.send('Debugger.resume');
    await page.mouse.up();
  }
  console.log(rosControl
    ? `Hold-to-run jogging on ${cell.cell.name}, ros_control backend (phone profile, ${REPS} runs each${QUICK ? ', quick' : ''}; the arm driver's joint states at 200 Hz)`
    : `Hold-to-run jogging on the simulated UR5 (phone profile, ${REPS} runs each${QUICK ? ', quick' : ''}; controller state at 500 Hz)`);
  console.log(`  Cartesian jog, release -> decelerating:  ${fmt(decel)}   (target <= 100 ms)`);
  console.log(`  Cartesian jog, release -> standstill:    ${fmt(still)}   (target <= 300 ms)`);
  console.log(`  joint jog, release -> standstill:        ${fmt(jointStill)}   (target <= 300 ms)`);
  console.log(`  browser frozen mid-jog -> standstill:     ${fmt(frozen)}   (target <= 500 ms)`);
  console.log(`  peak TCP speed, Cartesian jog at full slider: ${(peak * 1000).toFixed(1)} mm/s   (target <= 250 mm/s)`);
} finally {
  await browser.close();
  probe.kill('SIGTERM');
  await stopStack(stack.proc);
}
