// Alarms on a phone: a device fault raised on the simulated cell (/sim/trigger_fault stands for a real device)
// shows the banner and the menu badge on another page, is listed active, inactive once cleared, gone after Reset.
import { test, expect } from '@playwright/test';
import { loginAs, openMenu } from '../lib/app.js';
import { rosCli } from '../lib/ros.js';

const fault = (/** @type {string} */ f) => rosCli(`rosservice call /sim/trigger_fault "fault: '${f}'"`);

test.afterEach(async () => { await fault('reset'); });

test('a device fault: banner and badge on every page, active on the Alarms page, inactive when cleared, gone after Reset', async ({ page }) => {
  test.slow();
  await loginAs(page, 'admin', '/manual');
  const banner = page.getByRole('alert').filter({ hasText: /gripper/i });
  await expect(banner).toHaveCount(0);

  await fault('gripper_fault');
  await expect(banner).toBeVisible({ timeout: 10_000 });
  await expect(banner).toContainText('Error');
  await openMenu(page);
  await expect(page.getByTestId('nav-alarms-badge')).toBeVisible();
  await expect(page.getByTestId('nav-alarms-badge')).toContainText(/active alarm/);
  // The operation mode follows: an error alarm sets it to alarm.
  await expect(page.getByTestId('op-mode')).toHaveText(/alarm/i, { timeout: 10_000 });
  await page.getByTestId('nav-alarms').click();

  const item = page.locator('[data-testid="alarm"][data-alarm="device.gripper_fault"]');
  await expect(item).toHaveAttribute('data-active', 'true');
  await expect(item.getByTestId('alarm-activity')).toHaveText('Active');
  // Dismissed, the banner goes (the next alarm brings it back: app unit tests).
  await banner.getByRole('button', { name: 'Dismiss alarm banner' }).click();
  await expect(banner).toHaveCount(0);

  // Reset while the fault is there: it stays.
  await page.getByRole('button', { name: 'Reset', exact: true }).click();
  await expect(item).toHaveAttribute('data-active', 'true');

  await fault('reset');
  await expect(item).toHaveAttribute('data-active', 'false', { timeout: 10_000 });
  await expect(item.getByTestId('alarm-activity')).toHaveText('Inactive');
  await page.getByRole('button', { name: 'Reset', exact: true }).click();
  await expect(item).toHaveCount(0, { timeout: 10_000 });
});
