// The twin-arm cell's routines: a routine is taught for the motion group chosen on the Routines page
// (the right arm, with its own tool, the vacuum), and running it moves that arm through the taught poses while
// the other arm stays still. The arms are watched from outside the app, on the stack's rosbridge.
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs, goToPage } from '../lib/app.js';
import { watchRobot, watchTcp } from '../lib/robot.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const title = (/** @type {string} */ id) => cell.pages.find((/** @type {any} */ p) => p.id === id).title;
const [first, group] = cell.manual.groups.map((/** @type {any} */ g) => g.name); // teach the second arm
const tool = cell.manual.tools.find((/** @type {any} */ t) => t.group === group);

/** @type {import('../lib/robot.js').TcpWatch} */
let tcp;
/** @type {import('../lib/robot.js').RobotWatch} */
let arm;
/** @type {import('../lib/robot.js').RobotWatch} */
let otherArm;
test.beforeAll(async () => {
  tcp = await watchTcp(group);
  arm = await watchRobot(group);
  otherArm = await watchRobot(first);
});
test.afterAll(() => [tcp, arm, otherArm].forEach((w) => w?.close()));

/** In-app navigation (the draft lives in the app). @param {import('@playwright/test').Page} page @param {string} id */
const go = (page, id) => goToPage(page, title(id));

async function standstill() {
  await expect.poll(async () => (await arm.observe(25)).maxSpeed, { timeout: 10_000 }).toBeLessThan(1e-3);
}

/** Move the chosen arm by a relative offset (mm) on the Manual page. @param {import('@playwright/test').Page} page @param {Record<string, string>} offset */
async function moveRelative(page, offset) {
  await go(page, 'manual');
  await expect(page.getByRole('radiogroup', { name: 'Motion group' }).getByRole('radio', { name: group })).toBeChecked();
  for (const [k, v] of Object.entries(offset)) await page.getByTestId(`rel-${k}`).fill(v);
  await page.getByRole('button', { name: 'Move relative' }).click();
  await expect(page.getByTestId('move-relative-feedback')).toContainText(/arrived/i, { timeout: 30_000 });
  await standstill();
  for (const k of Object.keys(offset)) await page.getByTestId(`rel-${k}`).fill('');
}

/** Largest joint change since `before` (rad). @param {number[]} before @param {number[]} now */
const moved = (before, now) => Math.max(...now.map((q, i) => Math.abs(q - before[i])));

test('a routine taught for the second arm with its own tool runs on that arm only, through both poses within 1 mm', async ({ page }) => {
  test.slow();
  expect(tool, `a tool of group ${group} in the cell file`).toBeTruthy();
  await loginAs(page, 'admin');
  await go(page, 'manual');
  await page.getByRole('radiogroup', { name: 'Motion group' }).getByRole('radio', { name: group }).check();
  await page.getByRole('button', { name: 'Take control' }).click();
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');
  await page.getByRole('combobox', { name: 'Named configuration' }).selectOption('home');
  await page.getByRole('button', { name: 'Move to configuration' }).click();
  await expect(page.getByTestId('move-named-feedback')).toContainText(/arrived at home/i, { timeout: 30_000 });
  await standstill();
  const otherBefore = otherArm.joints();

  // The group first: the tools offered are that group's own.
  await go(page, 'routines');
  await page.getByRole('combobox', { name: 'Motion group' }).selectOption(group);
  const toolChoice = page.getByRole('combobox', { name: 'Tool', exact: true });
  await expect(toolChoice.getByRole('option')).toHaveText([tool.name]);
  await page.getByRole('combobox', { name: 'Tool action' }).selectOption({ label: `${tool.name[0].toUpperCase()}${tool.name.slice(1)} off` });
  const pose1 = tcp.pose();
  await page.getByRole('button', { name: 'Add pose' }).click();
  await page.getByRole('button', { name: 'Add action' }).click();
  const draft = page.getByTestId('routine-draft').getByRole('listitem');
  await expect(draft).toHaveCount(2);
  // A routine is for one group: it cannot change once steps are recorded.
  await expect(page.getByRole('combobox', { name: 'Motion group' })).toBeDisabled();

  await moveRelative(page, { dz: '-60' });
  await go(page, 'routines');
  const pose2 = tcp.pose();
  expect(Math.hypot(pose2[0] - pose1[0], pose2[1] - pose1[1], pose2[2] - pose1[2])).toBeGreaterThan(0.05);
  await page.getByRole('button', { name: 'Add pose' }).click();
  await expect(draft).toHaveCount(3);
  await page.getByRole('textbox', { name: 'Routine name' }).fill('e2e twin');
  await page.getByRole('button', { name: 'Save as' }).click();
  const saved = page.locator('[data-testid="routine"][data-routine="e2e twin"]');
  await expect(saved).toContainText('3 steps: 2 poses, 1 action');
  await expect(saved).toContainText(group);

  // Run it from somewhere else: this arm passes through both poses, the other one never moves.
  await moveRelative(page, { dy: '50' });
  await go(page, 'routines');
  const since = Date.now();
  await saved.getByRole('button', { name: 'Run e2e twin' }).click();
  await expect(saved.getByTestId('routine-run-feedback')).toContainText('Done', { timeout: 90_000 });
  await standstill();
  expect(tcp.closest(pose1, since)).toBeLessThan(0.001);
  const end = tcp.pose();
  expect(Math.hypot(end[0] - pose2[0], end[1] - pose2[1], end[2] - pose2[2])).toBeLessThan(0.001);
  expect(moved(otherBefore, otherArm.joints())).toBeLessThan(1e-3);

  await saved.getByRole('button', { name: 'Delete e2e twin' }).click();
  await page.getByRole('dialog').getByRole('button', { name: 'Delete e2e twin' }).click();
  await expect(saved).toHaveCount(0);
  await page.getByRole('button', { name: 'Release control' }).click();
});
