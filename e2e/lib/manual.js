// Manual-motion steps shared by the demo cell's Manual specs (manual.spec.js, manual-lease.spec.js).
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { expect } from '@playwright/test';
import { loginAs } from './app.js';
import { REPO_ROOT } from './stack.js';

export const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
export const arm = cell.manual.groups[0];
// A jog stopped: 50 consecutive /joint_states (0.4 s at 125 Hz) without joint motion. A jog that went on, even at
// a tenth of these tests' speed (0.05 rad/s), would travel 20 mrad in that time; the sim's stopped arm may still
// settle by up to about 1 mrad (CI saw 0.73 mrad with reported speeds under 3e-5 rad/s, and once a single reported
// speed of 1.2 mrad/s: PyBullet corrects contact and constraint errors mostly in position). So 2 mrad of travel,
// and no reported speed of 10 mrad/s or more (a fifth of that slowest jog).
export const STILL = { messages: 50, rad: 2e-3, speed: 1e-2 };

export const jogMsg = { group: arm.name, mode: 'joint', axis: 0, direction: 1, speed: 0.5, frame: 'base' };

/** @param {import('@playwright/test').Page} page @param {string} [who] */
export async function openManual(page, who = 'admin') {
  await loginAs(page, who);
  await page.goto('/manual');
  await expect(page.getByTestId('page-title')).toHaveText(cell.pages.find((/** @type {any} */ p) => p.id === 'manual').title);
}

/**
 * Wait for the arm to come to rest and stay at rest for STILL.messages joint states (within `timeout`). A release
 * that a stalled host delivers together with the heartbeats before it may first let the jog go on for a moment (the
 * driver jogs on when a stalled link's heartbeats come again, docs/ros-interfaces.md): CI once saw the arm at rest
 * at the release, then 0.14 rad/s. What must hold is that it stops and stays stopped; a jog that goes on never
 * shows a still window and fails here.
 * @param {import('./robot.js').RobotWatch} robot
 */
export async function expectStandstill(robot, timeout = 3_000) {
  const end = Date.now() + timeout;
  let after = await robot.observe(STILL.messages);
  while (!(after.travel < STILL.rad && after.maxSpeed < STILL.speed) && Date.now() < end) after = await robot.observe(STILL.messages);
  expect(after.travel, `travel over the last ${STILL.messages} joint states, ${timeout} ms after the release (their largest speed: ${after.maxSpeed} rad/s)`).toBeLessThan(STILL.rad);
  expect(after.maxSpeed, `the largest joint speed over those ${STILL.messages} joint states`).toBeLessThan(STILL.speed);
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
