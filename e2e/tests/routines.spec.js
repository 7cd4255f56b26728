// Routines on a phone, through the real page, BFF, rosbridge, the routines node and the robot driver (ur_rtde
// against the sim): an admin teaches two poses with a gripper action between them (moving the arm on the Manual
// page in between), saves, runs the routine from elsewhere (the arm reaches both poses within 1 mm), renames and
// deletes it.
import { test, expect } from '@playwright/test';
import { loginAs, openMenu } from '../lib/app.js';
import { watchTcp, watchRobot, expectAtRest } from '../lib/robot.js';

/** @type {import('../lib/robot.js').TcpWatch} */
let tcp;
/** @type {import('../lib/robot.js').RobotWatch} */
let robot;
test.beforeAll(async () => {
  tcp = await watchTcp();
  robot = await watchRobot();
});
test.afterAll(() => {
  tcp?.close();
  robot?.close();
});

/** In-app navigation (the draft lives in the app, and a reload is not what a user does). @param {import('@playwright/test').Page} page @param {string} title */
async function go(page, title) {
  await openMenu(page);
  await page.getByRole('navigation', { name: 'Main menu' }).getByRole('link', { name: title, exact: true }).click();
  await expect(page.getByTestId('page-title')).toHaveText(title);
}

/** @param {import('@playwright/test').Page} page */
async function standstill(page) {
  await expectAtRest(robot);
  void page;
}

/** Move the arm by a relative offset (mm) on the Manual page. @param {import('@playwright/test').Page} page @param {Record<string, string>} offset */
async function moveRelative(page, offset) {
  await go(page, 'Manual motion');
  for (const [k, v] of Object.entries(offset)) await page.getByTestId(`rel-${k}`).fill(v);
  await page.getByRole('button', { name: 'Move relative' }).click();
  await expect(page.getByTestId('move-relative-feedback')).toContainText(/arrived/i, { timeout: 30_000 });
  await standstill(page);
  for (const k of Object.keys(offset)) await page.getByTestId(`rel-${k}`).fill('');
}

test('an admin records two poses and a gripper action, runs the routine (both poses within 1 mm), renames and deletes it', async ({ page }) => {
  test.slow();
  await loginAs(page, 'admin');
  await go(page, 'Manual motion');
  await page.getByRole('button', { name: 'Take control' }).click();
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');
  await page.getByRole('combobox', { name: 'Named configuration' }).selectOption('home');
  await page.getByRole('button', { name: 'Move to configuration' }).click();
  await expect(page.getByTestId('move-named-feedback')).toContainText(/arrived at home/i, { timeout: 30_000 });
  await standstill(page);

  // Pose 1 where the arm is, then the gripper closing, then pose 2 after a move on the Manual page.
  await go(page, 'Routines');
  await page.getByRole('combobox', { name: 'Tool action' }).selectOption({ label: 'Gripper open' });
  await page.getByRole('button', { name: 'Add action' }).click();
  await expect(page.getByTestId('routine-draft').getByRole('listitem')).toHaveCount(1);
  const pose1 = tcp.pose();
  await page.getByRole('button', { name: 'Add pose' }).click();
  await page.getByRole('combobox', { name: 'Tool action' }).selectOption({ label: 'Gripper close' });
  await page.getByRole('button', { name: 'Add action' }).click();
  await expect(page.getByTestId('routine-draft').getByRole('listitem')).toHaveCount(3);
  await expect(page.getByTestId('routines-log')).toContainText('Gripper close recorded');

  await moveRelative(page, { dx: '-60', dz: '-80' });
  await go(page, 'Routines');
  await expect(page.getByTestId('routine-draft').getByRole('listitem')).toHaveCount(3);
  const pose2 = tcp.pose();
  expect(Math.hypot(pose2[0] - pose1[0], pose2[1] - pose1[1], pose2[2] - pose1[2])).toBeGreaterThan(0.08);
  await page.getByRole('button', { name: 'Add pose' }).click();
  await expect(page.getByTestId('routine-draft').getByRole('listitem')).toHaveCount(4);
  await expect(page.getByTestId('routines-log')).toContainText('Pose recorded');
  // Reorder: the pose before the open action goes first.
  await page.getByRole('button', { name: 'Move step 2 up' }).click();
  await expect(page.getByTestId('routine-draft').getByRole('listitem').first()).toContainText('Pose');

  // A name that would be a path is refused in place.
  const nameInput = page.getByRole('textbox', { name: 'Routine name' });
  await nameInput.fill('../etc/x');
  await expect(page.getByRole('button', { name: 'Save as' })).toBeDisabled();
  await nameInput.fill('e2e pick');
  await page.getByRole('button', { name: 'Save as' }).click();
  const saved = page.locator('[data-testid="routine"][data-routine="e2e pick"]');
  await expect(saved).toBeVisible();
  await expect(saved).toContainText('4 steps: 2 poses, 2 actions');
  await expect(page.getByTestId('routine-draft')).toHaveCount(0);
  // Its recorded poses as a path in the 3D view (a panel that opens on demand).
  const scene = page.getByTestId('routines-scene');
  await scene.getByRole('button', { name: 'Show 3D view' }).click();
  await saved.getByRole('button', { name: 'Show path of e2e pick' }).click();
  await expect(scene.getByTestId('scene-path')).toHaveText('Path of e2e pick: 2 recorded poses');
  await expect(scene.getByRole('img', { name: /3D view/ })).toBeVisible();

  // Run it from somewhere else.
  await moveRelative(page, { dy: '60' });
  await go(page, 'Routines');
  const since = Date.now();
  await saved.getByRole('button', { name: 'Run e2e pick' }).click();
  await expect(saved.getByTestId('routine-run-feedback')).toContainText('Done', { timeout: 90_000 });
  await standstill(page);
  expect(tcp.closest(pose1, since)).toBeLessThan(0.001);
  const end = tcp.pose();
  expect(Math.hypot(end[0] - pose2[0], end[1] - pose2[1], end[2] - pose2[2])).toBeLessThan(0.001);
  await expect(page.getByTestId('routines-log')).toContainText('e2e pick done');

  // Rename, then delete with confirmation.
  await saved.getByRole('button', { name: 'Rename e2e pick' }).click();
  await page.getByRole('textbox', { name: 'New name for e2e pick' }).fill('e2e pick 2');
  await page.getByRole('button', { name: 'Save name' }).click();
  const renamed = page.locator('[data-testid="routine"][data-routine="e2e pick 2"]');
  await expect(renamed).toBeVisible();
  await expect(saved).toHaveCount(0);
  await renamed.getByRole('button', { name: 'Delete e2e pick 2' }).click();
  await page.getByRole('dialog').getByRole('button', { name: 'Delete e2e pick 2' }).click();
  await expect(renamed).toHaveCount(0);
  await expect(page.getByTestId('routines-log')).toContainText(/deleted/i);

  await page.getByRole('button', { name: 'Release control' }).click();
});
