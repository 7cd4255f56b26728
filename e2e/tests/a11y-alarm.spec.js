// Accessibility audit with an active alarm: its banner, the red badges and the Alarms page (lib/a11y.js).
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { audit, keepResults } from '../lib/a11y.js';
import { simFault, clearSimFault, recorderIdle } from '../lib/ros.js';

keepResults('alarm');

test('with an active alarm (its banner, red badges, the Alarms page) every theme has no serious or critical violation', async ({ page }) => {
  test.setTimeout(180_000);
  await loginAs(page, 'admin');
  await simFault('gripper_fault');
  try {
    await page.goto('/alarms');
    await expect(page.locator('[data-testid="alarm"][data-alarm="device.gripper_fault"][data-active="true"]')).toBeVisible({ timeout: 20_000 });
    /** @type {string[]} */
    const problems = [];
    for (const url of ['/', '/alarms', '/process', '/manual', '/modules']) problems.push(...(await audit(page, url, 'alarm')));
    expect(problems).toEqual([]);
  } finally {
    await clearSimFault();
    await recorderIdle();
  }
});
