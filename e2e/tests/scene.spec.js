// The 3D view (issue 24) on the demo cell, through the real page, BFF (the URDF from /robot_description), rosbridge,
// driver and simulated UR5, on the tablet profile. The view's drawn joint values (its "Joint
// values" readout, read from the drawn model) are compared with /joint_states watched from outside the app.
import { test, expect } from '@playwright/test';
import { goToPage, loginAs } from '../lib/app.js';
import { watchRobot } from '../lib/robot.js';
import { cell, arm, openManual } from '../lib/manual.js';

/** @type {import('../lib/robot.js').RobotWatch} */
let robot;
test.beforeAll(async () => { robot = await watchRobot(); });
test.afterAll(() => robot?.close());

/**
 * The view's drawn joint values, in the group's joint order.
 * @param {import('@playwright/test').Locator} view @returns {Promise<number[]>}
 */
async function drawn(view) {
  return Promise.all(arm.joints.map(async (/** @type {string} */ j) => {
    const v = await view.locator(`[data-testid="scene-joint"][data-joint="${j}"]`).getAttribute('data-value');
    return v ? Number(v) : NaN;
  }));
}

/** @param {number[]} a @param {number[]} b */
const maxDiff = (a, b) => Math.max(...a.map((v, i) => (Number.isFinite(v) ? Math.abs(v - b[i]) : Infinity)));

test('the 3D view beside the Manual controls follows the arm (within 0.01 rad after a named move); a relative move\'s ghost is where the arm ends up; an unreachable target says so before anything moves', async ({ page }) => {
  await openManual(page);
  const panel = page.getByTestId('manual-scene');
  // A panel that opens on demand (beside the controls on a tablet or a PC, below the jog pad on a phone).
  await panel.getByRole('button', { name: 'Show 3D view' }).click();
  await expect(panel.getByRole('img', { name: /3D view/ })).toBeVisible();

  await page.getByRole('button', { name: 'Take control' }).click();
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');
  // The named configuration farthest from where the arm is: the view must follow a real move.
  const here = robot.joints();
  const [name, target] = /** @type {[string, number[]]} */ (Object.entries(arm.configurations)
    .sort(([, a], [, b]) => maxDiff(/** @type {number[]} */ (b), here) - maxDiff(/** @type {number[]} */ (a), here))[0]);
  expect(maxDiff(target, here)).toBeGreaterThan(0.1);
  await page.getByRole('combobox', { name: 'Named configuration' }).selectOption(name);
  await page.getByRole('button', { name: 'Move to configuration' }).click();
  await expect(page.getByTestId('move-named-feedback')).toContainText(new RegExp(`arrived at ${name}`, 'i'), { timeout: 30_000 });
  await expect.poll(async () => maxDiff(await drawn(panel), robot.joints()), { timeout: 5_000 }).toBeLessThan(0.01);
  expect(maxDiff(robot.joints(), target)).toBeLessThan(0.01);
  await expect(panel.getByTestId('scene-stale')).toHaveCount(0);

  // A relative move is previewed before it runs: the driver's target drawn as a ghost, where the arm then ends up.
  await page.getByRole('textbox', { name: 'dZ (mm)' }).fill('30');
  await expect(page.getByTestId('move-preview')).toHaveText('Target shown in the 3D view (ghost).');
  /** @returns {Promise<number[]>} */
  const ghost = () => Promise.all(arm.joints.map(async (/** @type {string} */ j) => {
    const v = await panel.locator(`[data-testid="scene-joint"][data-joint="${j}"]`).getAttribute('data-target');
    return v ? Number(v) : NaN;
  }));
  await expect.poll(async () => maxDiff(await ghost(), robot.joints()), { timeout: 5_000 }).toBeGreaterThan(0.005);
  const previewed = await ghost();
  await page.getByRole('button', { name: 'Move relative' }).click();
  await expect(page.getByTestId('move-relative-feedback')).toContainText(/arrived/i, { timeout: 30_000 });
  await expect.poll(() => robot.speed(), { timeout: 10_000 }).toBeLessThan(1e-3);
  // Joints within 1 mrad: at the UR5's reach (< 1 m) the TCP within 5 mm.
  expect(maxDiff(previewed, robot.joints())).toBeLessThan(0.001);
  // The move ran: its ghost is gone. An unreachable target says so before anything moves.
  await expect(page.getByTestId('move-preview')).toHaveCount(0);
  await page.getByRole('textbox', { name: 'dZ (mm)' }).fill('5000');
  await expect(page.getByTestId('move-preview')).toContainText(/^Unreachable: /);
  await page.getByRole('textbox', { name: 'dZ (mm)' }).fill('');
  await page.getByRole('button', { name: 'Release control' }).click();
});

test('Home has the 3D view card; the 3D view page has camera presets, Reset view and the cell\'s parts', async ({ page }) => {
  await loginAs(page, 'operator');
  const card = page.getByTestId('home-scene');
  await expect(card.getByRole('img', { name: /3D view/ })).toBeVisible();
  await expect.poll(async () => maxDiff(await drawn(card), robot.joints()), { timeout: 10_000 }).toBeLessThan(0.01);

  await goToPage(page, cell.pages.find((/** @type {any} */ p) => p.id === 'scene').title);
  const view = page.getByTestId('scene-view');
  await expect(view.getByRole('img', { name: /3D view/ })).toBeVisible();
  for (const name of ['Top view', 'Side view', 'Front view', 'Reset view']) {
    await expect(view.getByRole('button', { name })).toBeEnabled();
    await view.getByRole('button', { name }).click();
  }
  // The sim's cubes and fixture from the cell's MarkerArray topic.
  await expect(view.getByTestId('scene-objects')).toHaveText(new RegExp(`^([3-9]|\\d\\d+) objects from ${cell.scene.markers}$`));
  await expect(view.getByRole('alert')).toHaveCount(0);
});
