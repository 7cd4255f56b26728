// Diagnostics as alarms, on the tablet: the Vision module's monitor reports on /diagnostics; killed (kill -9),
// its status turns STALE on the Inspect page and raises the alarm the demo cell's rule gives it; started again, it
// reports and the alarm goes inactive. The module is stopped at the end, as the next specs expect it (inactive), and
// a module stopped on purpose leaves no stale alarm behind.
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs, goToPage } from '../lib/app.js';
import { nodePid, rosCli, rosCliRunning } from '../lib/ros.js';
import { REPO_ROOT } from '../lib/stack.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
const vision = cell.modules.find((/** @type {any} */ m) => m.nodes.includes('/vision_monitor'));
const STATUS = 'vision: camera brightness';
const ALARM = 'diagnostics.vision_camera_brightness';

test('a module node killed: its diagnostics go stale and raise the alarm; started again, the alarm clears', async ({ page }) => {
  test.slow();
  let monitor = null;
  await loginAs(page, 'admin', '/modules');
  const card = page.locator(`[data-testid="module"][data-module="${vision.name}"]`);
  try {
    await expect(card).toHaveAttribute('data-state', 'inactive', { timeout: 15_000 });
    await page.getByRole('button', { name: `Launch ${vision.name}` }).click();
    await expect(card).toHaveAttribute('data-state', 'active', { timeout: 30_000 });

    await goToPage(page, 'Inspect');
    await page.getByRole('tab', { name: 'Diagnostics' }).click();
    const row = page.locator(`[data-testid="diag-status"][data-name="${STATUS}"]`);
    await expect(row).toHaveAttribute('data-level', /^(ok|warn)$/, { timeout: 15_000 });

    // Killed from a terminal: no more reports; 5 s later the status is STALE and the rule's alarm is active.
    const pid = await nodePid('/vision_monitor');
    expect(pid).toBeGreaterThan(1);
    process.kill(/** @type {number} */ (pid), 'SIGKILL');
    await expect(row).toHaveAttribute('data-level', 'stale', { timeout: 15_000 });
    await expect(row).toContainText(/stale/i);

    await page.goto('/alarms');   // (the menu's Alarms link carries the active-alarm badge in its name)
    const alarm = page.locator(`[data-testid="alarm"][data-alarm="${ALARM}"]`);
    await expect(alarm).toHaveAttribute('data-active', 'true', { timeout: 10_000 });
    await expect(alarm).toContainText('no report for 5 s');

    // Started again by hand: it reports, the alarm goes inactive.
    monitor = rosCliRunning('rosrun cell_nodes vision_monitor_node __name:=vision_monitor');
    await expect(alarm).toHaveAttribute('data-active', 'false', { timeout: 20_000 });
  } finally {
    // As the next specs expect it: the hand-started monitor gone, the module stopped.
    monitor?.kill('SIGINT');
    const r = await rosCli(`rosservice call /cell/modules/stop "name: '${vision.name}'"`);
    expect(r.stdout).toContain('success: True');
    await page.goto('/modules');
    await expect(card).toHaveAttribute('data-state', 'inactive', { timeout: 20_000 });
  }
  // Stopped on purpose: the Inspect page shows the status STALE (5 s after the last report, as before), but the
  // alarms node forgot the stopped module's statuses: no stale alarm; Reset clears the inactive one.
  await goToPage(page, 'Inspect');
  await page.getByRole('tab', { name: 'Diagnostics' }).click();
  await expect(page.locator(`[data-testid="diag-status"][data-name="${STATUS}"]`)).toHaveAttribute('data-level', 'stale', { timeout: 15_000 });
  await page.goto('/alarms');
  const alarm = page.locator(`[data-testid="alarm"][data-alarm="${ALARM}"]`);
  await expect(alarm).toHaveAttribute('data-active', 'false');
  await rosCli('rosservice call /cell/alarms/reset');
  await expect(alarm).toHaveCount(0, { timeout: 10_000 });
});
