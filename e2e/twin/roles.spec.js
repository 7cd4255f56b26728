// The twin-arm cell's third role, `maintenance`, sees and may do exactly what config/twin-arm-cell.yaml says: its
// pages in the menu, its pages' APIs, its features' reads and commands through /ros, and nothing that moves an arm
// (checked through /ros and the API, not only in the menu); yet, like every role with a page, it can stop the robot
// ("Stop robot" on every page, /cell/manual/stop without the lease).
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs, openMenu, sessionCookie, rosSocket } from '../lib/app.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const role = cell.roles.maintenance;
const allPages = cell.pages.map((/** @type {any} */ p) => p.id);

test('maintenance sees its pages and only those, in the menu and through the API', async ({ page }) => {
  expect(role, 'the twin cell has a maintenance role').toBeTruthy();
  await loginAs(page, 'maintenance');
  await openMenu(page);
  for (const id of allPages) {
    await expect(page.getByTestId(`nav-${id}`), id).toHaveCount(role.pages.includes(id) ? 1 : 0);
  }
  const config = await (await page.request.get('/api/config')).json();
  expect(config.pages.map((/** @type {any} */ p) => p.id).sort()).toEqual([...role.pages].sort());
  // Pages it does not see: their APIs are refused, and so is the page itself.
  if (!role.pages.includes('system')) expect((await page.request.get('/api/audit')).status()).toBe(403);
  if (!role.pages.includes('database')) expect((await page.request.get('/api/database/files')).status()).toBe(403);
  // No command of its moves the robot: it may not hold control either (it would only keep the others from it).
  expect((await page.request.post('/api/control/take', { data: {} })).status()).toBe(403);
  // But it stops the robot: "Stop robot" is in the top bar of every page it sees (issue 28).
  expect(config.stop).toEqual({ service: '/cell/manual/stop', type: 'std_srvs/Trigger' });
  for (const id of role.pages) {
    await page.goto(id === 'home' ? '/' : `/${id}`);
    await expect(page.getByTestId('page-title'), id).toBeVisible();
    await expect(page.getByRole('button', { name: 'Stop robot' }), id).toBeEnabled();
  }
  for (const id of ['manual', 'process', 'routines'].filter((p) => !role.pages.includes(p))) {
    await page.goto(`/${id}`);
    await expect(page.getByTestId('access-denied'), id).toBeVisible();
  }
});

test('maintenance commands modules, resets alarms and stops the robot through /ros, and nothing that moves an arm goes through', async ({ page, context, baseURL }) => {
  await loginAs(page, 'maintenance');
  const ros = await rosSocket(String(baseURL), await sessionCookie(context));
  /** @param {string} id @param {string} service @param {object} args */
  const call = async (id, service, args) => {
    ros.send({ op: 'call_service', id, service, args });
    return ros.waitFor((m) => m.op === 'service_response' && m.id === id);
  };
  const denied = (/** @type {any} */ r) => r.result === false && String(r.values).includes('permission denied');

  // Its features' reads.
  ros.send({ op: 'subscribe', id: 's1', topic: '/cell/modules/state' });
  await ros.waitFor((m) => m.op === 'publish' && m.topic === '/cell/modules/state');
  ros.send({ op: 'subscribe', id: 's2', topic: '/cell/alarms/list' });
  await ros.waitFor((m) => m.op === 'publish' && m.topic === '/cell/alarms/list');

  // Its commands: a module whose roles list it launches and stops; the alarm reset is answered by the node.
  const mine = cell.modules.find((/** @type {any} */ m) => m.launch && m.roles.includes('maintenance'));
  const other = cell.modules.find((/** @type {any} */ m) => !m.roles.includes('maintenance'));
  expect(mine, 'a launchable module for maintenance').toBeTruthy();
  const launched = await call('m1', '/cell/modules/launch', { name: mine.name });
  expect(denied(launched)).toBe(false);
  expect(launched.values.success, JSON.stringify(launched.values)).toBe(true);
  expect(denied(await call('m2', '/cell/modules/stop', { name: mine.name }))).toBe(false);
  if (other) expect(denied(await call('m3', '/cell/modules/launch', { name: other.name }))).toBe(true);
  const reset = await call('r1', '/cell/alarms/reset', {});
  expect(denied(reset)).toBe(false);
  expect(reset.result).toBe(true);

  // The robot stop, without the lease: the node answers it (both arms stand still).
  const stopped = await call('s3', '/cell/manual/stop', {});
  expect(denied(stopped)).toBe(false);
  expect(stopped.result, JSON.stringify(stopped.values)).toBe(true);

  // Never motion: moves, tool actions, the process and routines are refused before they reach ROS.
  const group = cell.manual.groups[0].name;
  expect(denied(await call('x1', '/cell/manual/move_named', { group, name: 'home', speed: 0, acceleration: 0 }))).toBe(true);
  expect(denied(await call('x2', '/cell/manual/tool', { tool: cell.manual.tools[0].name, action: cell.manual.tools[0].actions[0].name }))).toBe(true);
  expect(denied(await call('x3', '/cell/process/start', { cycles: 1 }))).toBe(true);
  expect(denied(await call('x4', '/cell/routines/run', { name: 'x' }))).toBe(true);
  if (!role.commands.includes('parameters')) expect(denied(await call('x5', '/cell/parameters/set', { changes: [] }))).toBe(true);
  ros.send({ op: 'publish', id: 'j1', topic: '/cell/manual/jog', msg: { group, mode: 'joint', axis: 0, direction: 1, speed: 0.5, frame: 'base' } });
  expect((await ros.waitFor((m) => m.op === 'status' && m.id === 'j1')).level).toBe('error');
  ros.ws.close();
});
