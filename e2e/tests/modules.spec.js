// Modules on a phone, through the real page, BFF, rosbridge and the modules node (roslaunch): launch, a node killed
// from a terminal, stop; an operator sees and may launch only the modules its role lists (page, /api/config, /ros).
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs, sessionCookie, rosSocket } from '../lib/app.js';
import { nodePid } from '../lib/ros.js';
import { REPO_ROOT } from '../lib/stack.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
// A launchable module with two nodes or more (so that killing one leaves it incomplete), and one the operator lists.
const multi = cell.modules.find((/** @type {any} */ m) => m.launch?.length && m.nodes.length >= 2 && m.roles?.includes('admin'));
const forOperator = cell.modules.filter((/** @type {any} */ m) => !m.roles || m.roles.includes('operator')).map((/** @type {any} */ m) => m.name);
const adminOnly = cell.modules.find((/** @type {any} */ m) => m.launch?.length && m.roles && !m.roles.includes('operator'));

/** @param {import('@playwright/test').Page} page @param {string} name */
const card = (page, name) => page.locator(`[data-testid="module"][data-module="${name}"]`);

test('an admin launches a module (transitioning, then active), a node killed with kill -9 makes it incomplete, Stop makes it inactive', async ({ page }) => {
  test.slow();
  await loginAs(page, 'admin', '/modules');
  const c = card(page, multi.name);
  await expect(c).toHaveAttribute('data-state', 'inactive', { timeout: 15_000 });
  // Every state the card goes through, seen by the page itself (a poll could miss a short one).
  await c.evaluate((el) => {
    const w = /** @type {any} */ (window);
    w.__states = [el.getAttribute('data-state')];
    new MutationObserver(() => w.__states.push(el.getAttribute('data-state'))).observe(el, { attributes: true, attributeFilter: ['data-state'] });
  });
  await page.getByRole('button', { name: `Launch ${multi.name}` }).click();
  await expect(c).toHaveAttribute('data-state', 'active', { timeout: 30_000 });
  const seen = await page.evaluate(() => /** @type {any} */ (window).__states);
  expect(seen.indexOf('transitioning')).toBeGreaterThan(0);
  expect(seen.indexOf('transitioning')).toBeLessThan(seen.indexOf('active'));
  await expect(c.getByTestId('module-state')).toHaveText('Active');
  await expect(c.getByRole('button', { name: `Launch ${multi.name}` })).toBeDisabled();

  // A node killed from a terminal: incomplete within 3 s, with the dead node named.
  const victim = multi.nodes[multi.nodes.length - 1];
  const pid = await nodePid(victim);
  expect(pid).toBeGreaterThan(1);
  process.kill(/** @type {number} */ (pid), 'SIGKILL');
  await expect(c).toHaveAttribute('data-state', 'incomplete', { timeout: 3_000 });
  await expect(c.getByTestId('module-state')).toHaveText('Incomplete');
  await expect(c.getByRole('list', { name: `Nodes of ${multi.name}` })).toContainText(`${victim} not running`);

  await page.getByRole('button', { name: `Stop ${multi.name}` }).click();
  await expect(c).toHaveAttribute('data-state', 'inactive', { timeout: 20_000 });
  await expect(c.getByTestId('module-state')).toHaveText('Inactive');
});

test('an operator sees only the modules its role may launch, and cannot launch another one through /ros', async ({ page, context, baseURL }) => {
  await loginAs(page, 'operator', '/modules');
  await expect(page.getByTestId('module')).toHaveCount(forOperator.length);
  for (const name of forOperator) await expect(card(page, name)).toBeVisible();
  await expect(page.getByRole('button', { name: `Launch ${adminOnly.name}` })).toHaveCount(0);
  const cfg = await (await page.request.get('/api/config')).json();
  expect(cfg.features.modules.modules.map((/** @type {any} */ m) => m.name)).toEqual(forOperator);

  const ros = await rosSocket(baseURL, await sessionCookie(context));
  ros.send({ op: 'call_service', id: 'l1', service: '/cell/modules/launch', args: { name: adminOnly.name } });
  const refused = await ros.waitFor((m) => m.op === 'status' && m.id === 'l1');
  expect(refused.level).toBe('error');
  expect(refused.msg).toMatch(/may not launch or stop/);
  ros.ws.close();
});
