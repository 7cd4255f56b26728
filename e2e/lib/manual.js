// Manual-motion steps shared by the demo cell's Manual specs (manual.spec.js, manual-lease.spec.js).
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { expect } from '@playwright/test';
import { loginAs } from './app.js';
import { REPO_ROOT } from './stack.js';

export const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
export const arm = cell.manual.groups[0];
export { STILL, expectStandstill } from './robot.js';

export const jogMsg = { group: arm.name, mode: 'joint', axis: 0, direction: 1, speed: 0.5, frame: 'base' };

/** @param {import('@playwright/test').Page} page @param {string} [who] */
export async function openManual(page, who = 'admin') {
  await loginAs(page, who);
  await page.goto('/manual');
  await expect(page.getByTestId('page-title')).toHaveText(cell.pages.find((/** @type {any} */ p) => p.id === 'manual').title);
}

/**
 * Hold a jog button down (mouse: the pointer events a thumb would send) until the arm moves.
 * @param {import('@playwright/test').Page} page @param {import('./robot.js').RobotWatch} robot @param {string} name
 */
export async function holdJog(page, robot, name) {
  const before = robot.joints();
  await page.getByRole('button', { name, exact: true }).hover();
  await page.mouse.down();
  // 15 s: the first command after the stack starts has the driver upload and start ur_rtde's control script
  // first (CI: 5.5 s from the press to the script running, on a loaded host); later jogs start at once.
  await expect.poll(() => Math.max(...robot.joints().map((q, i) => Math.abs(q - before[i]))), { timeout: 15_000 }).toBeGreaterThan(0.01);
}
