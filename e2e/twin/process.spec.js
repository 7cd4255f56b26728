// The twin-arm cell's process: one cycle hands a cube over from the left arm (gripper) to the right arm
// (vacuum tool) through the stand, through the real page, BFF, process nodes, both robot drivers (ur_rtde) and the
// simulated cell. Where the cube ends up is read from outside the app: the sim's ground truth (/sim/objects).
// Cycle N takes cube and pocket (N - 1) mod 3; the sim's feeder puts the cubes back first, so the spec runs again
// on the same stack (another profile, --repeat-each) with its cube away from its pocket.
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { watchParts } from '../lib/robot.js';
import { cycleEntry } from '../lib/process.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const stations = cell.simulation.stations;
const pockets = stations.find((/** @type {any} */ s) => s.kind === 'fixture').pockets;
const stand = stations.find((/** @type {any} */ s) => s.kind === 'stand');

test('one cycle hands the cycle\'s cube over from the left arm to the right arm and into its pocket', async ({ page }) => {
  test.setTimeout(240_000);
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
    // The cube passes the stand (the left arm put it there), then ends in the right arm's pocket.
    await expect.poll(() => near(stand.position, 0.02), { timeout: 120_000, intervals: [200] }).toBe(true);
    await expect(page.getByTestId('process-operation')).toContainText(/stand|fixture|home/, { timeout: 60_000 });
    await expect(state).toHaveText(/Idle|Error/, { timeout: 150_000 });
    expect(await state.textContent(), String(await page.getByTestId('process-message').textContent().catch(() => ''))).toBe('Idle');
    await expect(page.getByTestId('process-cycles-done')).toHaveText('1');
    await expect.poll(() => near(pocket, 0.005), { timeout: 5_000 }).toBe(true);
    expect(sim.parts()[k].z).toBeLessThan(0.04);
    await page.getByRole('button', { name: 'Release control' }).click();
  } finally {
    sim.close();
  }
});
