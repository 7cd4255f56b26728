// Supervision, seen from the phone: the BFF dies (kill -9), the stack's supervisor restarts it, and the open
// app shows "reconnecting", then "connected" again and live data, without a reload and without a new login.
import fs from 'node:fs';
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';

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
