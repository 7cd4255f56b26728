// The control lease on the Manual page: one session holds control, another one's jog is refused, an admin's
// take-over stops the holder's jog. Two sessions in one browser, on every profile.
import { test, expect } from '@playwright/test';
import { sessionCookie, rosSocket } from '../lib/app.js';
import { watchRobot } from '../lib/robot.js';
import { cell, jogMsg, openManual, expectStandstill, holdJog } from '../lib/manual.js';

/** @type {import('../lib/robot.js').RobotWatch} */
let robot;
test.beforeAll(async () => { robot = await watchRobot(); });
test.afterAll(() => robot?.close());

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
    // (Two sessions in one browser: the holder's tab comes to the front, as on its own device.)
    await page.bringToFront();
    // No notice of lost control (if there is one, the failure shows its reason).
    await expect(page.getByTestId('lease-lost')).toHaveCount(0);
    await expect(page.getByTestId('lease-holder')).toContainText('You have control');
    await holdJog(page, robot, 'Jog joint 1 -');
    await second.getByRole('button', { name: 'Take over control' }).click();
    await expect(second.getByTestId('lease-holder')).toContainText('You have control');
    await expectStandstill(robot);
    await expect(page.getByTestId('lease-lost')).toBeVisible();
    await page.mouse.up();
    await second.getByRole('button', { name: 'Release control' }).click();
  } finally {
    await other.close();
  }
});

test('a page busy for longer than the lease timeout keeps control (its heartbeats do not wait for the page); a page hung for good loses it', async ({ page }) => {
  await openManual(page);
  await page.getByRole('button', { name: 'Take control' }).click();
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');
  const timeoutMs = cell.control.heartbeat_timeout_s * 1000;
  /** Keep the page's main thread busy, as a slow device laying out a page does. */
  const busy = (/** @type {number} */ ms) => page.evaluate((ms) => {
    const t = performance.now();
    while (performance.now() - t < ms) { /* busy */ }
  }, ms);
  const serverView = () => page.evaluate(async () => (await fetch('/api/control', { cache: 'no-store' })).json());

  await busy(timeoutMs + 2000);
  expect((await serverView()).you).toBe(true);
  await expect(page.getByTestId('lease-holder')).toContainText('You have control');
  await expect(page.getByTestId('lease-lost')).toHaveCount(0);

  // Hung for a lease timeout, the worker stops beating; one more, and the server ends the lease; the page says so
  // when it wakes.
  await busy(2 * timeoutMs + 3000);
  await expect(page.getByTestId('lease-lost')).toContainText(/expired|no heartbeat/i);
  expect((await serverView()).you).toBe(false);
  await expect(page.getByRole('button', { name: 'Jog joint 1 +', exact: true })).toBeDisabled();
});
