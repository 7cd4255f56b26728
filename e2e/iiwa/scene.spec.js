// The iiwa cell's 3D view: the arm's URDF comes from its own driver's robot_description (ros_control), with the
// KUKA meshes (STL, file:// URIs on the robot PC) served through the BFF; drawn at the driver's joint states.
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { watchRobot } from '../lib/robot.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const group = cell.manual.groups[0];

/** @type {import('../lib/robot.js').RobotWatch} */
let robot;
test.beforeAll(async () => { robot = await watchRobot(); });
test.afterAll(() => robot?.close());

test('the 3D view draws the iiwa from its driver\'s URDF with its meshes, at its joint states', async ({ page }) => {
  /** @type {string[]} */
  const meshes = [];
  page.on('response', (r) => { if (r.url().includes('/meshes/')) meshes.push(`${r.status()} ${r.url()}`); });
  await loginAs(page, 'operator', '/scene');
  const view = page.getByTestId('scene-view');
  await expect(view.getByRole('img', { name: /3D view/ })).toBeVisible();
  await expect.poll(async () => {
    const drawn = await Promise.all(group.joints.map(async (/** @type {string} */ j) => Number(await view.locator(`[data-testid="scene-joint"][data-joint="${j}"]`).getAttribute('data-value') || NaN)));
    const actual = robot.joints();
    return Math.max(...drawn.map((v, i) => (Number.isFinite(v) ? Math.abs(v - actual[i]) : Infinity)));
  }, { timeout: 10_000 }).toBeLessThan(0.01);
  // Every link mesh came through the BFF (no problem shown in place).
  await expect.poll(() => meshes.length, { timeout: 10_000 }).toBeGreaterThanOrEqual(group.joints.length);
  expect(meshes.filter((m) => !m.startsWith('200 '))).toEqual([]);
  await expect(view.getByRole('alert')).toHaveCount(0);
});
