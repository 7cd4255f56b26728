// Supervision, seen from the phone: the BFF dies (kill -9), the stack's supervisor restarts it, and the open
// app shows "reconnecting", then "connected" again and live data, without a reload and without a new login.
import fs from 'node:fs';
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { watchRobot } from '../lib/robot.js';
import { openManual, expectStandstill, holdJog } from '../lib/manual.js';

/** The e2e stack's BFF: the process with its DATA_DIR in its environment running bff/src/server.js. */
function bffPid() {
  const dataDir = `DATA_DIR=${process.env.E2E_DATA_DIR}`;
  for (const d of fs.readdirSync('/proc')) {
    if (!/^\d+$/.test(d)) continue;
    try {
      if (!fs.readFileSync(`/proc/${d}/cmdline`, 'utf8').includes('bff/src/server.js')) continue;
      if (/\) Z /.test(fs.readFileSync(`/proc/${d}/stat`, 'utf8'))) continue;
      if (fs.readFileSync(`/proc/${d}/environ`, 'utf8').split('\0').includes(dataDir)) return Number(d);
    } catch { /* gone, or not ours */ }
  }
  return null;
}

test('kill -9 of the BFF: the app reads "reconnecting", then "connected" with live data again, no reload, still signed in', async ({ page }) => {
  test.setTimeout(120_000);
  await loginAs(page, 'admin');
  await expect(page).toHaveURL(/\/$/);
  const conn = page.getByTestId('home-conn');
  await expect(conn).toHaveText('connected');
  // Live data from ROS: the modules card (the modules node publishes its state every second).
  const modules = page.getByTestId('home-modules-freshness');
  await expect(modules).toHaveAttribute('data-stale', 'false');
  await expect(modules).toContainText(/\d+ of \d+/);

  await page.evaluate(() => { /** @type {any} */ (window).__beforeCrash = 'still here'; });
  const navigations = [];
  page.on('framenavigated', (f) => { if (f === page.mainFrame()) navigations.push(f.url()); });
  const pid = bffPid();
  expect(pid, 'the e2e stack runs a BFF').toBeGreaterThan(1);

  const t0 = Date.now();
  process.kill(/** @type {number} */ (pid), 'SIGKILL');
  await expect(conn).toHaveText('reconnecting');
  await expect(modules).toHaveAttribute('data-stale', 'true'); // no longer live while the link is down
  await expect.poll(() => bffPid(), { timeout: 30_000 }).not.toBe(pid);
  await expect(conn).toHaveText('connected', { timeout: 45_000 });
  const took = (Date.now() - t0) / 1000;
  test.info().annotations.push({ type: 'recovery', description: `"connected" again ${took} s after the SIGKILL` });
  console.log(`recovery: the app reads "connected" again ${took} s after the BFF's SIGKILL`);

  // Live data again, on the same page (no reload: the marker is still there), and still signed in.
  await expect(modules).toHaveAttribute('data-stale', 'false', { timeout: 15_000 });
  expect(await page.evaluate(() => /** @type {any} */ (window).__beforeCrash)).toBe('still here');
  expect(navigations).toEqual([]);
  await expect(page).not.toHaveURL(/\/login/);
  const me = await page.request.get('/api/auth/me');
  expect(me.status(), 'the session cookie from before the crash is still valid').toBe(200);
  expect((await me.json()).username).toBe('admin');
  await expect(page.getByTestId('home-user')).toContainText('admin');
});

test('kill -9 of the BFF during a jog: the arm stops at once; the BFF is back within the heartbeat timeout and the holder keeps control', async ({ page }) => {
  test.setTimeout(120_000);
  const robot = await watchRobot();
  try {
    await openManual(page);
    await page.getByRole('button', { name: 'Take control' }).click();
    const holder = page.getByTestId('lease-holder');
    await expect(holder).toContainText('You have control');
    await holdJog(page, robot, 'Jog joint 1 -');
    const pid = bffPid();
    expect(pid, 'the e2e stack runs a BFF').toBeGreaterThan(1);
    const t0 = Date.now();
    process.kill(/** @type {number} */ (pid), 'SIGKILL');
    // The BFF answers again (measured from here, for the report: the lease survives if this is within 2 s).
    const back = (async () => {
      await expect.poll(async () => (await fetch(new URL('/api/auth/me', test.info().project.use.baseURL)).catch(() => null))?.status ?? 0,
        { timeout: 30_000, intervals: [20] }).toBe(401);
      return (Date.now() - t0) / 1000;
    })();
    // The thumb is still on the button: the link dropped, so the driver's heartbeat watchdog stops the arm.
    await expectStandstill(robot);
    await page.mouse.up();
    const took = await back;
    test.info().annotations.push({ type: 'recovery', description: `the BFF answered again ${took} s after the SIGKILL` });
    console.log(`recovery: the BFF answered again ${took} s after its SIGKILL`);

    // The supervisor restarts the BFF at once; the lease it saved comes back to its holder.
    const kept = page.getByRole('status').filter({ hasText: 'Control kept' });
    await expect(kept).toContainText('the server restarted and gave control back to you', { timeout: 30_000 });
    await expect(holder).toContainText('You have control');
    await expect(page.getByTestId('lease-lost')).toHaveCount(0);
    await kept.getByRole('button', { name: 'Dismiss the control notice' }).click();
    await expect(kept).toHaveCount(0);

    // And it moves again, once the app is connected again.
    await expect(page.getByRole('button', { name: 'Jog joint 1 +', exact: true })).toBeEnabled({ timeout: 30_000 });
    const q0 = robot.joints()[0];
    await holdJog(page, robot, 'Jog joint 1 +');
    await page.mouse.up();
    await expectStandstill(robot);
    expect(robot.joints()[0]).toBeGreaterThan(q0);
    await page.getByRole('button', { name: 'Release control' }).click();
    await expect(holder).not.toContainText('You have control');
  } finally {
    robot.close();
  }
});
