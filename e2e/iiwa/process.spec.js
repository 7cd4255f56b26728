// The iiwa cell's process: one cycle picks a cube with the vacuum cup and puts it into its pocket of the fixture (cycle
// N takes cube and pocket (N - 1) mod 3; the sim's feeder puts the cubes back first, so the spec runs again), through the real page, BFF, process nodes, our driver's ros_control backend and the
// simulated iiwa driver. Where the cube ends up is read from outside the app: the sim's ground truth (/sim/objects).
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { watchParts } from '../lib/robot.js';
import { cycleEntry } from '../lib/process.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const pockets = cell.simulation.stations.find((/** @type {any} */ s) => s.kind === 'fixture').pockets;
const base = cell.simulation.arms[0].base; // the arm's base in the world: the poses are in its frame

test('one cycle picks the cycle\'s cube with the vacuum cup and places it in its pocket', async ({ page }) => {
  test.setTimeout(240_000);
  expect(base.slice(0, 2)).toEqual([0, 0]);
  const sim = await watchParts();
  try {
    await loginAs(page, 'operator', '/process');
    const state = page.getByTestId('process-state');
    // Not running (Error when a run before this one ended in one: it shows until the next Start).
    await expect(state).toHaveText(/^(Idle|Error)$/, { timeout: 30_000 });
    await sim.restock();
    await page.getByRole('button', { name: 'Take control' }).click();
    await expect(page.getByTestId('lease-holder')).toContainText('You have control');
    await page.getByRole('textbox', { name: 'Cycles' }).fill('1');
    await page.getByRole('button', { name: 'Start', exact: true }).click();
    const dialog = page.getByRole('dialog', { name: 'Start away from the start position?' });
    await expect(dialog.or(state.filter({ hasText: 'Running' }))).toBeVisible({ timeout: 15_000 });
    if (await dialog.isVisible()) await dialog.getByRole('button', { name: 'Start anyway' }).click();
    await expect(state).toHaveText('Running');
    const k = await cycleEntry(page, pockets.length);
    const pocket = pockets[k];
    const near = (/** @type {number[]} */ [x, y], tol = 0.01) => Math.hypot(sim.parts()[k].x - x, sim.parts()[k].y - y) < tol;
    expect(near(pocket, 0.05), `cube ${k + 1} starts away from its pocket`).toBe(false);
    // The cube is lifted off the table on the way (held by the cup), then rests in the pocket.
    await expect.poll(() => sim.parts()[k].z, { timeout: 90_000, intervals: [100] }).toBeGreaterThan(0.05);
    await expect(state).toHaveText(/Idle|Error/, { timeout: 150_000 });
    expect(await state.textContent(), String(await page.getByTestId('process-message').textContent().catch(() => ''))).toBe('Idle');
    await expect(page.getByTestId('process-cycles-done')).toHaveText('1');
    await expect.poll(() => near(pocket, 0.006), { timeout: 5_000 }).toBe(true);
    expect(sim.parts()[k].z).toBeLessThan(0.04);
    await page.getByRole('button', { name: 'Release control' }).click();
  } finally {
    sim.close();
  }
});
