// The plant page on the phone (the issue asks for it): the demo cell's stack and a second cell (the twin
// cell's BFF, its ROS side not started) report on the stack's mosquitto as Sparkplug B edge nodes; the demo cell's
// plant page lists both; a device fault on the demo cell shows there as an alarm within 1 s of its alarm status on
// ROS; a cell's link opens that cell's own login.
import { test, expect } from '@playwright/test';
import WebSocket from 'ws';
import { loginAs, goToPage } from '../lib/app.js';
import { simFault as fault, clearSimFault, recorderIdle } from '../lib/ros.js';
import { otherCell } from '../lib/plant.js';

/** @type {{base: string, stop: () => void}} */
let twin;
test.beforeAll(async () => { twin = await otherCell('config/twin-arm-cell.yaml', /** @type {string} */ (process.env.E2E_PLANT_BROKER_URL)); });
test.afterAll(() => twin?.stop());
test.afterEach(async () => {
  await clearSimFault();
  await recorderIdle();
});

test('the plant page lists both cells; a fault on one shows as its alarm within 1 s; its link opens that cell\'s login', async ({ page }) => {
  await loginAs(page, 'admin');
  await goToPage(page, 'Plant');
  const demo = page.getByTestId('plant-cell-demo-ur5');
  const other = page.getByTestId('plant-cell-twin-arm');
  await expect(demo).toHaveAttribute('data-status', 'ok', { timeout: 10_000 });
  await expect(demo).toContainText('Demo UR5 cell');
  await expect(demo.getByTestId('plant-cell-online')).toContainText(/Online since/);
  await expect(other).toContainText('Twin-arm hand-over cell');
  await expect(other.getByTestId('plant-cell-ros')).toHaveText('ROS link down');
  await expect(page.getByTestId('plant-count')).toContainText('2 cells');
  // The shift so far, as the plant view counted it (this stack's demo cell runs no process here).
  await expect(demo.getByTestId('plant-cell-shift')).toContainText(/^\d+ cycles? in the last hour · running \d+ % of /);

  // The alarm status on ROS (the stack's rosbridge, as the plant reporter reads it): the clock starts there.
  const ws = new WebSocket(/** @type {string} */ (process.env.E2E_ROSBRIDGE_URL));
  try {
    await new Promise((r, j) => { ws.once('open', r); ws.once('error', j); });
    /** @type {Promise<number>} */
    const raised = new Promise((resolve) => ws.on('message', (d) => {
      const m = JSON.parse(d.toString());
      if (m.op === 'publish' && m.msg?.active_count > 0) resolve(Date.now());
    }));
    ws.send(JSON.stringify({ op: 'subscribe', topic: '/cell/alarms/status', type: 'cell_msgs/SafetyStatus' }));
    await fault('gripper_fault');
    const at = await raised;
    await expect(demo).toHaveAttribute('data-status', 'alarm', { timeout: Math.max(1, at + 1000 - Date.now()) });
    test.info().annotations.push({ type: 'alarm on the plant page', description: `${Date.now() - at} ms after its status on ROS` });
  } finally { ws.close(); }
  await expect(demo.getByTestId('plant-cell-alarm')).toContainText(/gripper/i);
  // Alarms first.
  await expect(page.locator('[data-testid^="plant-cell-"][data-status]').first()).toHaveAttribute('data-testid', 'plant-cell-demo-ur5');

  // The other cell's link: its own UI, where nobody is signed in yet.
  const link = other.getByRole('link', { name: 'Open Twin-arm hand-over cell' });
  await expect(link).toHaveAttribute('href', `${twin.base}/`);
  const [opened] = await Promise.all([page.context().waitForEvent('page'), link.click()]);
  await expect(opened).toHaveURL(/\/login/);
  await expect(opened.getByTestId('login-username')).toBeVisible();
  await opened.close();
});
