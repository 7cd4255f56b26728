// The iiwa cell's routines: two poses and a vacuum action are taught, saved, and the routine replayed
// from elsewhere passes through both poses within 1 mm (our driver's linear moves on the ros_control backend).
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs, goToPage } from '../lib/app.js';
import { watchRobot, watchTcp } from '../lib/robot.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const title = (/** @type {string} */ id) => cell.pages.find((/** @type {any} */ p) => p.id === id).title;
const tool = cell.manual.tools[0];

/** @type {import('../lib/robot.js').TcpWatch} */
let tcp;
/** @type {import('../lib/robot.js').RobotWatch} */
let arm;
test.beforeAll(async () => { tcp = await watchTcp(); arm = await watchRobot(); });
test.afterAll(() => [tcp, arm].forEach((w) => w?.close()));

/** In-app navigation (the draft lives in the app). @param {import('@playwright/test').Page} page @param {string} id */
const go = (page, id) => goToPage(page, title(id));

async function standstill() {
  await expect.poll(async () => (await arm.observe(40)).maxSpeed, { timeout: 10_000 }).toBeLessThan(1e-3);
}

/** @param {import('@playwright/test').Page} page @param {Record<string, string>} offset mm */
async function moveRelative(page, offset) {
  await go(page, 'manual');
  for (const [k, v] of Object.entries(offset)) await page.getByTestId(`rel-${k}`).fill(v);
  await page.getByRole('button', { name: 'Move relative' }).click();
  await expect(page.getByTestId('move-relative-feedback')).toContainText(/arrived/i, { timeout: 30_000 });
  await standstill();
  for (const k of Object.keys(offset)) await page.getByTestId(`rel-${k}`).fill('');
}

/** @param {number[]} a @param {number[]} b */
const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);

test('a routine of two poses and a vacuum action is recorded, saved and replayed through both poses within 1 mm', async ({ page }) => {
  test.slow();
  await loginAs(page, 'admin');
  await go(page, 'manual');
  await page.getByRole('button', { name: 'Take control' }).click();
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');
  await page.getByRole('combobox', { name: 'Named configuration' }).selectOption('home');
  await page.getByRole('button', { name: 'Move to configuration' }).click();
  await expect(page.getByTestId('move-named-feedback')).toContainText(/arrived at home/i, { timeout: 30_000 });
  await standstill();

  await go(page, 'routines');
  await page.getByRole('combobox', { name: 'Tool action' }).selectOption({ label: `${tool.name[0].toUpperCase()}${tool.name.slice(1)} off` });
  const pose1 = tcp.pose();
  await page.getByRole('button', { name: 'Add pose' }).click();
  await page.getByRole('button', { name: 'Add action' }).click();
  const draft = page.getByTestId('routine-draft').getByRole('listitem');
  await expect(draft).toHaveCount(2);

  await moveRelative(page, { dz: '-60', dx: '40' });
  await go(page, 'routines');
  const pose2 = tcp.pose();
  expect(dist(pose1, pose2)).toBeGreaterThan(0.06);
  await page.getByRole('button', { name: 'Add pose' }).click();
  await expect(draft).toHaveCount(3);
  await page.getByRole('textbox', { name: 'Routine name' }).fill('e2e iiwa');
  await page.getByRole('button', { name: 'Save as' }).click();
  const saved = page.locator('[data-testid="routine"][data-routine="e2e iiwa"]');
  await expect(saved).toContainText('3 steps: 2 poses, 1 action');

  await moveRelative(page, { dy: '50' });
  await go(page, 'routines');
  const since = Date.now();
  await saved.getByRole('button', { name: 'Run e2e iiwa' }).click();
  await expect(saved.getByTestId('routine-run-feedback')).toContainText('Done', { timeout: 90_000 });
  await standstill();
  expect(tcp.closest(pose1, since)).toBeLessThan(0.001);
  expect(dist(tcp.pose(), pose2)).toBeLessThan(0.001);

  await saved.getByRole('button', { name: 'Delete e2e iiwa' }).click();
  await page.getByRole('dialog').getByRole('button', { name: 'Delete e2e iiwa' }).click();
  await expect(saved).toHaveCount(0);
  await page.getByRole('button', { name: 'Release control' }).click();
});
