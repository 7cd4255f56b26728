// The iiwa cell's process on a phone: one cycle picks the first cube with the vacuum cup and puts it into the first
// pocket of the fixture, through the real page, BFF, process nodes, our driver's ros_control backend and the
// simulated iiwa driver. Where the cube ends up is read from outside the app: the sim's ground truth (/sim/objects).
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { watchParts } from '../lib/robot.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const pocket = cell.simulation.stations.find((/** @type {any} */ s) => s.kind === 'fixture').pockets[0];
const base = cell.simulation.arms[0].base; // the arm's base in the world: the poses are in its frame

test('one cycle picks the first cube with the vacuum cup and places it in the first pocket', async ({ page }) => {
  test.setTimeout(240_000);
  expect(base.slice(0, 2)).toEqual([0, 0]);
  const sim = await watchParts();
  try {
    const near = (/** @type {number[]} */ [x, y], tol = 0.01) => {
      const p = sim.parts()[0];
      return Math.hypot(p.x - x, p.y - y) < tol;
    };
    expect(near(pocket, 0.05), 'the first cube starts away from the pocket').toBe(false);
    await loginAs(page, 'operator');
    await page.goto('/process');
    const state = page.getByTestId('process-state');
    await expect(state).toHaveText('Idle', { timeout: 30_000 });
    await page.getByRole('button', { name: 'Take control' }).click();
    await expect(page.getByTestId('lease-holder')).toContainText('You have control');
    await page.getByRole('textbox', { name: 'Cycles' }).fill('1');
    await page.getByRole('button', { name: 'Start', exact: true }).click();
    const dialog = page.getByRole('dialog', { name: 'Start away from the start position?' });
    await expect(dialog.or(state.filter({ hasText: 'Running' }))).toBeVisible({ timeout: 15_000 });
    if (await dialog.isVisible()) await dialog.getByRole('button', { name: 'Start anyway' }).click();
    await expect(state).toHaveText('Running');
    // The cube is lifted off the table on the way (held by the cup), then rests in the pocket.
    await expect.poll(() => sim.parts()[0].z, { timeout: 90_000, intervals: [100] }).toBeGreaterThan(0.05);
    await expect(state).toHaveText('Idle', { timeout: 150_000 });
    await expect(page.getByTestId('process-cycles-done')).toHaveText('1');
    await expect.poll(() => near(pocket, 0.006), { timeout: 5_000 }).toBe(true);
    expect(sim.parts()[0].z).toBeLessThan(0.04);
    await page.getByRole('button', { name: 'Release control' }).click();
  } finally {
    sim.close();
  }
});
