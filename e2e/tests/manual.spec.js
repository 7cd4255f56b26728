// Manual motion on a phone, through the real page, BFF, rosbridge, driver (ur_rtde) and the simulated UR5.
// The arm is watched from outside the app (the driver's /joint_states on the stack's rosbridge).
// Runs on the phone profile (playwright.config.js): the hold-to-run pad is a thumb control.
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs, sessionCookie, rosSocket } from '../lib/app.js';
import { watchRobot } from '../lib/robot.js';
import { REPO_ROOT } from '../lib/stack.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
const arm = cell.manual.groups[0];
// A jog stopped: 50 consecutive /joint_states (0.4 s at 125 Hz) without joint motion.
const STILL = { messages: 50, rad: 1e-4 };

/** @type {import('../lib/robot.js').RobotWatch} */
let robot;
test.beforeAll(async () => { robot = await watchRobot(); });
test.afterAll(() => robot?.close());

/** @param {import('@playwright/test').Page} page */
async function openManual(page, who = /** @type {'admin'|'operator'} */ ('admin')) {
  await loginAs(page, who);
  await page.goto('/manual');
  await expect(page.getByTestId('page-title')).toHaveText(cell.pages.find((/** @type {any} */ p) => p.id === 'manual').title);
}

/** Wait for the arm to stand still, then check it stays still. */
async function expectStandstill(timeout = 3_000) {
  await expect.poll(() => robot.speed(), { timeout, intervals: [20] }).toBeLessThan(1e-3);
  const after = await robot.observe(STILL.messages);
  expect(after.travel).toBeLessThan(STILL.rad);
}

/** Hold a jog button down (mouse: the pointer events a thumb would send) until the arm moves. */
async function holdJog(page, name) {
  const before = robot.joints();
  await page.getByRole('button', { name, exact: true }).hover();
  await page.mouse.down();
  await expect.poll(() => Math.max(...robot.joints().map((q, i) => Math.abs(q - before[i]))), { timeout: 5_000 }).toBeGreaterThan(0.01);
}

const jogMsg = { group: arm.name, mode: 'joint', axis: 0, direction: 1, speed: 0.5, frame: 'base' };

test('an admin takes control, moves to a named configuration, jogs, and the arm stops on release', async ({ page }) => {
  await openManual(page);
  const jog = page.getByRole('button', { name: 'Jog joint 1 +', exact: true });
  await expect(jog).toBeDisabled();
  await page.getByRole('button', { name: 'Take control' }).click();
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');

  const [name, target] = Object.entries(arm.configurations).find(([n]) => n !== 'home') ?? [];
  await page.getByRole('combobox', { name: 'Motion group' }).selectOption(arm.name);
  await page.getByRole('combobox', { name: 'Named configuration' }).selectOption(String(name));
  await page.getByRole('button', { name: 'Move to configuration' }).click();
  await expect(page.getByText(new RegExp(`arrived at ${name}`, 'i')).first()).toBeVisible({ timeout: 30_000 });
  robot.joints().forEach((q, i) => expect(Math.abs(q - /** @type {number[]} */ (target)[i])).toBeLessThan(0.01));

  await expect(jog).toBeEnabled();
  const q0 = robot.joints()[0];
  await holdJog(page, 'Jog joint 1 +');
  await page.mouse.up();
  await expectStandstill();
  expect(robot.joints()[0]).toBeGreaterThan(q0 + 0.01);
  await page.getByRole('button', { name: 'Release control' }).click();
  await expect(jog).toBeDisabled();
});

test('an operator sees the Manual page but cannot move the arm, and is told why', async ({ page, context, baseURL }) => {
  await openManual(page, 'operator');
  for (const name of ['Jog joint 1 +', 'Move to configuration', 'Gripper close']) {
    await expect(page.getByRole('button', { name, exact: true })).toBeDisabled();
  }
  await page.getByRole('radio', { name: 'Cartesian jog' }).check();
  await expect(page.getByRole('button', { name: 'Jog X -', exact: true })).toBeDisabled();
  await expect(page.getByText(/role may not/i).first()).toBeVisible();
  await expect(page.getByRole('button', { name: 'Stop robot' })).toBeEnabled();

  // The server refuses it too: a jog and a move sent straight to /ros with the operator's cookie.
  const ros = await rosSocket(baseURL, await sessionCookie(context));
  const before = robot.joints();
  ros.send({ op: 'publish', id: 'j1', topic: '/cell/manual/jog', msg: jogMsg });
  expect((await ros.waitFor((m) => m.op === 'status' && m.id === 'j1')).level).toBe('error');
  ros.send({ op: 'call_service', id: 'm1', service: '/cell/manual/move_named', args: { group: arm.name, name: 'home', speed: 0, acceleration: 0 } });
  expect((await ros.waitFor((m) => m.op === 'service_response' && m.id === 'm1')).result).toBe(false);
  const after = await robot.observe(STILL.messages);
  expect(after.travel).toBeLessThan(STILL.rad);
  robot.joints().forEach((q, i) => expect(Math.abs(q - before[i])).toBeLessThan(STILL.rad));
  ros.ws.close();
});

test('one session holds control: another one\'s jog is refused; an admin take-over stops the holder\'s jog', async ({ page, browser, baseURL }) => {
  await openManual(page);
  await page.getByRole('button', { name: 'Take control' }).click();
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');

  const other = await browser.newContext({ ...test.info().project.use, baseURL });
  const second = await other.newPage();
  try {
    await openManual(second);
    await expect(second.getByTestId('lease-holder')).toContainText('has control');
    await expect(second.getByRole('button', { name: 'Jog joint 1 +', exact: true })).toBeDisabled();
    const ros = await rosSocket(baseURL, await sessionCookie(other));
    ros.send({ op: 'publish', id: 'j2', topic: '/cell/manual/jog', msg: jogMsg });
    const refused = await ros.waitFor((m) => m.op === 'status' && m.id === 'j2');
    expect(refused.level).toBe('error');
    expect(refused.msg).toMatch(/control/i);
    ros.ws.close();

    // The holder jogs and keeps the button held; the second admin takes control over: the arm stops.
    await holdJog(page, 'Jog joint 1 -');
    await second.getByRole('button', { name: 'Take over control' }).click();
    await expect(second.getByTestId('lease-holder')).toContainText('You have control');
    await expectStandstill();
    await expect(page.getByTestId('lease-lost')).toBeVisible();
    await page.mouse.up();
    await second.getByRole('button', { name: 'Release control' }).click();
  } finally {
    await other.close();
  }
});
