#!/usr/bin/env node
// The 3D view's frame rate while the arm moves, through the real page (Chromium), the BFF, rosbridge, the driver and
// the simulated demo cell: the arm goes back and forth between two named configurations (a rosbridge client on the
// stack's loopback rosbridge port calls /cell/manual/move_named, as a second session would), while the 3D view page
// is shown on a desktop profile (CPU as is) and on a phone profile (Pixel 7, CPU throttled 4x, as a mid-range phone).
// Measured in the page: the frames the view drew per second (its own counter: it draws only on a change) and the
// page's animation frames per second; then the same with the arm standing still (the view should draw nothing).
// Targets: >= 30 fps on the desktop, >= 20 fps on the phone at 4x, while the arm moves.
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { WebSocket } from 'ws';
import { chromium, devices } from '@playwright/test';
import { stackEnv, addUser, startStack, stopStack, REPO_ROOT } from '../e2e/lib/stack.js';

const QUICK = process.env.BENCH_QUICK === '1';
const SECONDS = Number(process.env.BENCH_DURATION_S || (QUICK ? 3 : 8));
const port = 38580;
const cellFile = path.join(REPO_ROOT, 'config/demo-cell.yaml');
const cell = /** @type {any} */ (yaml.load(fs.readFileSync(cellFile, 'utf8')));
const group = cell.manual.groups[0];
const [c1, c2] = Object.keys(group.configurations);
const env = stackEnv({ port, masterPort: port + 1, rosbridgePort: port + 2, urHost: '127.0.0.29', extraEnv: { CELL_CONFIG: cellFile } });
addUser(env, 'bench', 'operator', 'bench-password');

/** Keeps the arm moving between two named configurations until stopped (a plain rosbridge client). */
function mover() {
  const ws = new WebSocket(`ws://127.0.0.1:${env.ROSBRIDGE_PORT}`);
  let running = false;
  let n = 0;
  /** @type {((v: any) => void) | null} */
  let answer = null;
  ws.on('message', (d) => {
    const m = JSON.parse(d.toString());
    if (m.op === 'service_response' && answer) answer(m);
  });
  const call = (name) => new Promise((resolve) => {
    answer = resolve;
    ws.send(JSON.stringify({ op: 'call_service', id: `m${n++}`, service: '/cell/manual/move_named', args: { group: group.name, name, speed: 0, acceleration: 0 } }));
  });
  let loop = Promise.resolve();
  return {
    opened: new Promise((r) => ws.once('open', r)),
    start() {
      running = true;
      loop = (async () => {
        let to = c1;
        while (running) {
          const r = await call(to);
          if (!r.result || !r.values?.success) throw new Error(`move_named ${to}: ${JSON.stringify(r.values ?? r)}`);
          to = to === c1 ? c2 : c1;
        }
      })();
    },
    async stop() {
      running = false;
      await loop;
    },
    close: () => ws.close(),
  };
}

// BENCH_GPU=swiftshader: Chromium treats SwiftShader as a GPU (ANGLE), so it composites the page on that "GPU" as a
// phone's Chromium does on its real one, instead of software compositing, which reads every WebGL frame back to the
// renderer and waits for it (docs/performance.md, "3D view"). Still all on this machine's CPU.
const GPU = process.env.BENCH_GPU === 'swiftshader'
  ? ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'] : [];
const stack = await startStack(env);
const browser = await chromium.launch({ executablePath: process.env.CHROMIUM_PATH || '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run', ...GPU] });
const arm = mover();
try {
  await arm.opened;
  console.log(`3D view, demo cell, the arm moving ${c1} <-> ${c2} (move_named, default speed), ${SECONDS} s per run${QUICK ? ' (quick)' : ''}, compositing: ${GPU.length ? 'GPU (SwiftShader)' : 'software'}`);
  console.log('  profile                  | arm     | view frames/s | page animation frames/s');
  for (const [name, device, rate] of [['desktop (Desktop Chrome)', 'Desktop Chrome', 1], ['phone (Pixel 7), CPU 4x', 'Pixel 7', 4]]) {
    const context = await browser.newContext({ ...devices[device], baseURL: `http://localhost:${port}` });
    const page = await context.newPage();
    await page.goto('/login');
    await page.getByTestId('login-username').fill('bench');
    await page.getByTestId('login-password').fill('bench-password');
    await page.getByTestId('login-submit').click();
    await page.waitForURL((u) => !u.pathname.startsWith('/login'));
    await page.goto('/scene');
    const view = page.getByTestId('scene-view');
    await view.getByRole('img').waitFor({ timeout: 30_000 });
    await page.locator('[data-testid="scene-joint"][data-value]:not([data-value=""])').first().waitFor({ timeout: 30_000 });
    const cdp = await context.newCDPSession(page);
    await cdp.send('Emulation.setCPUThrottlingRate', { rate });
    for (const moving of [true, false]) {
      if (moving) arm.start();
      await page.waitForTimeout(1000);
      const f0 = await page.evaluate(() => Number(document.querySelector('[data-testid="scene-view"]')?.getAttribute('data-frames')));
      const raf = await page.evaluate((seconds) => new Promise((resolve) => {
        let n = 0;
        const t0 = performance.now();
        const tick = (t) => {
          n++;
          if (t - t0 < seconds * 1000) requestAnimationFrame(tick);
          else resolve({ n, span: (t - t0) / 1000 });
        };
        requestAnimationFrame(tick);
      }), SECONDS);
      // The counter on the page is refreshed every 250 ms: wait one refresh so the span matches.
      await page.waitForTimeout(300);
      const f1 = await page.evaluate(() => Number(document.querySelector('[data-testid="scene-view"]')?.getAttribute('data-frames')));
      const span = raf.span + 0.3;
      console.log(`  ${name.padEnd(24)} | ${(moving ? 'moving' : 'still').padEnd(7)} | ${((f1 - f0) / span).toFixed(1).padStart(13)} | ${(raf.n / raf.span).toFixed(1).padStart(23)}`);
      if (moving) await arm.stop();
    }
    await cdp.send('Emulation.setCPUThrottlingRate', { rate: 1 });
    await context.close();
  }
  console.log('  targets: >= 30 view frames/s on the desktop and >= 20 on the phone at 4x while the arm moves; ~0 while still');
} finally {
  arm.close();
  await browser.close();
  await stopStack(stack.proc);
}
