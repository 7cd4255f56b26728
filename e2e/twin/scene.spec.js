// The twin-arm cell's 3D view: both arms, each from its own URDF parameter and placed where it stands, moved by the
// one /joint_states both drivers share (each arm picks its own joint names), with the cell's parts.
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { watchRobot } from '../lib/robot.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const groups = cell.manual.groups;

/** @type {Record<string, import('../lib/robot.js').RobotWatch>} */
const arms = {};
test.beforeAll(async () => {
  for (const g of groups) arms[g.name] = await watchRobot(g.name);
});
test.afterAll(() => Object.values(arms).forEach((a) => a.close()));

test('the 3D view shows both arms, each drawn at its own joint states, and the parts', async ({ page }) => {
  expect(groups.length).toBe(2);
  await loginAs(page, 'operator', '/scene');
  const view = page.getByTestId('scene-view');
  await expect(view.getByRole('img', { name: /3D view/ })).toBeVisible();
  for (const g of groups) {
    await expect(view.getByRole('table', { name: `Joint values of ${g.name}` })).toBeVisible();
    await expect.poll(async () => {
      const drawn = await Promise.all(g.joints.map(async (/** @type {string} */ j) => Number(await view.locator(`[data-testid="scene-joint"][data-group="${g.name}"][data-joint="${j}"]`).getAttribute('data-value') || NaN)));
      const actual = arms[g.name].joints();
      return Math.max(...drawn.map((v, i) => (Number.isFinite(v) ? Math.abs(v - actual[i]) : Infinity)));
    }, { timeout: 10_000 }).toBeLessThan(0.01);
  }
  await expect(view.getByTestId('scene-objects')).toHaveText(new RegExp(`^\\d+ objects from ${cell.scene.markers}$`));
  await expect(view.getByRole('alert')).toHaveCount(0);
});

test('each arm stands where TF puts its base frame: where the simulated cell built it', async ({ page }) => {
  expect(cell.scene.fixed_frame).toBeTruthy();
  await loginAs(page, 'operator', '/scene');
  const view = page.getByTestId('scene-view');
  for (const arm of cell.scene.arms) {
    const sim = cell.simulation.arms.find((/** @type {any} */ a) => a.group === arm.group);
    const base = view.locator(`[data-testid="scene-base"][data-group="${arm.group}"]`);
    await expect(base).toHaveText(new RegExp(`base from TF, ${arm.base_frame} in ${cell.scene.fixed_frame} at x ${sim.base[0].toFixed(3)}, `));
    const p = String(await base.getAttribute('data-position')).split(',').map(Number);
    const q = String(await base.getAttribute('data-quaternion')).split(',').map(Number);
    p.forEach((v, i) => expect(Math.abs(v - sim.base[i])).toBeLessThan(0.001));
    const yaw = (Math.atan2(2 * q[3] * q[2], 1 - 2 * q[2] * q[2]) * 180) / Math.PI;
    expect(Math.abs((((yaw - sim.base[3]) % 360) + 540) % 360 - 180)).toBeLessThan(0.1);
  }
});
