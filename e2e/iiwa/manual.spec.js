// The iiwa cell's Manual page, through the real page, BFF, rosbridge, our driver's ros_control backend
// and the simulated iiwa driver (FollowJointTrajectory, the trajectory controller's command topic). The arm is
// watched from outside the app: its own driver's joint states and our driver's TCP state, on the stack's rosbridge.
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { watchRobot, watchTcp } from '../lib/robot.js';
import { rosCli } from '../lib/ros.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const group = cell.manual.groups[0];
const fault = (/** @type {string} */ f) => rosCli(`rosservice call /sim/trigger_fault "fault: '${f}'"`);

/** @type {import('../lib/robot.js').RobotWatch} */
let arm;
/** @type {import('../lib/robot.js').TcpWatch} */
let tcp;
test.beforeAll(async () => { arm = await watchRobot(); tcp = await watchTcp(); });
test.afterAll(() => { arm?.close(); tcp?.close(); });
// Whatever a test left behind, the next one starts without a blocked arm or an alarm.
test.afterEach(async () => {
  await fault('reset');
  await rosCli('rosservice call /cell/alarms/reset');
});

async function standstill() {
  await expect.poll(async () => (await arm.observe(40)).maxSpeed, { timeout: 10_000 }).toBeLessThan(1e-3);
}

/** @param {import('@playwright/test').Page} page */
async function takeControl(page) {
  await loginAs(page, 'admin', '/manual');
  await page.getByRole('button', { name: 'Take control' }).click();
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');
}

/** @param {import('@playwright/test').Page} page @param {string} name */
async function moveNamed(page, name) {
  await page.getByRole('combobox', { name: 'Named configuration' }).selectOption(name);
  await page.getByRole('button', { name: 'Move to configuration', exact: true }).click();
}

test('a named move arrives on all 7 joints, a joint jog stops on release, a relative move goes 50 mm up', async ({ page }) => {
  test.slow();
  expect(group.joints).toHaveLength(7);
  await takeControl(page);
  for (const name of ['pick_approach', 'home']) {
    await moveNamed(page, name);
    await expect(page.getByTestId('move-named-feedback')).toContainText(new RegExp(`arrived at ${name}`, 'i'), { timeout: 30_000 });
    await standstill();
    arm.joints().forEach((q, i) => expect(Math.abs(q - group.configurations[name][i]), `joint ${i + 1}`).toBeLessThan(0.01));
  }

  // Hold-to-run: joint 7 turns while the button is held and stops on release.
  const before = arm.joints();
  await page.getByRole('button', { name: 'Jog joint 7 +', exact: true }).hover();
  await page.mouse.down();
  await expect.poll(() => arm.joints()[6] - before[6], { timeout: 5_000 }).toBeGreaterThan(0.02);
  await page.mouse.up();
  await expect.poll(() => arm.speed(), { timeout: 1_000, intervals: [10] }).toBeLessThan(1e-3);
  const still = await arm.observe(60);
  expect(still.travel).toBeLessThan(1e-4);
  arm.joints().slice(0, 6).forEach((q, i) => expect(Math.abs(q - before[i])).toBeLessThan(1e-3));

  // A straight move 50 mm up in the base frame, from the URDF's kinematics.
  const start = tcp.pose();
  await page.getByTestId('rel-dz').fill('50');
  await page.getByRole('button', { name: 'Move relative' }).click();
  await expect(page.getByTestId('move-relative-feedback')).toContainText(/arrived/i, { timeout: 30_000 });
  await standstill();
  const end = tcp.pose();
  expect(Math.abs(end[2] - start[2] - 0.05)).toBeLessThan(0.001);
  expect(Math.hypot(end[0] - start[0], end[1] - start[1])).toBeLessThan(0.001);
  await page.getByRole('button', { name: 'Release control' }).click();
});

test('a trajectory the controller aborts (the arm is blocked) fails the move with its reason and raises an alarm', async ({ page }) => {
  test.slow();
  await takeControl(page);
  await moveNamed(page, 'home');
  await expect(page.getByTestId('move-named-feedback')).toContainText(/arrived at home/i, { timeout: 30_000 });
  await standstill();
  try {
    await fault('collision');
    await moveNamed(page, 'pick_approach');
    await expect(page.getByText(/aborted the trajectory: PATH_TOLERANCE_VIOLATED/).first()).toBeVisible({ timeout: 30_000 });
    const banner = page.getByRole('alert').filter({ hasText: /aborted the trajectory/ });
    await expect(banner.first()).toBeVisible();
    await standstill();
  } finally {
    await fault('reset');
  }
  // The next command clears the arm's fault: the move succeeds, the alarm is inactive and goes with Reset.
  await moveNamed(page, 'home');
  await expect(page.getByTestId('move-named-feedback')).toContainText(/arrived at home/i, { timeout: 30_000 });
  await page.goto('/alarms');
  const item = page.locator('[data-testid="alarm"][data-alarm="robot.arm.motion_fault"]');
  await expect(item).toHaveAttribute('data-active', 'false', { timeout: 10_000 });
  await page.getByRole('button', { name: 'Reset', exact: true }).click();
  await expect(item).toHaveCount(0, { timeout: 10_000 });
  await expect(page.getByTestId('op-mode')).not.toHaveText(/alarm/i, { timeout: 10_000 });
});
