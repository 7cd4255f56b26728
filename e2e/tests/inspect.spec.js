// The Inspect page's ROS log on the desktop: a warning a demo node logs (the parameters node refusing a value
// sent by an engineer's `rosservice call`) appears with its node and level; the level, node and text filters narrow
// the list; the entry is still there after a reload (the inspect node's history); the filtered entries export as
// a text file. An operator, who does not see the page, cannot call the history through /ros.
import fs from 'node:fs';
import { test, expect } from '@playwright/test';
import { loginAs, goToPage, sessionCookie, rosSocket } from '../lib/app.js';
import { rosCli } from '../lib/ros.js';

test('a warning logged by a node: listed with its node and level, filtered, kept across a reload, exported', async ({ page }) => {
  test.slow();
  await loginAs(page, 'admin');
  await goToPage(page, 'Inspect');
  await expect(page.getByTestId('inspect-history')).toContainText('History');
  const tag = `e2e-${test.info().project.name}-${Date.now()}`;
  // Not a whole number: the parameters node refuses it and logs a warning saying why, with the caller.
  const r = await rosCli(`rosservice call /cell/parameters/set "changes: [{id: parts_per_cycle, value: '${tag}'}]"`);
  expect(r.stdout).toContain('success: False');

  const log = page.getByRole('list', { name: 'ROS log' });
  const mine = log.getByTestId('log-entry').filter({ hasText: tag });
  await expect(mine).toHaveCount(1, { timeout: 15_000 });
  await expect(mine).toHaveAttribute('data-level', 'warn');
  await expect(mine).toHaveAttribute('data-node', '/parameters');
  await expect(mine).toContainText('WARN');
  await expect(mine).toContainText('set refused');

  // Level: errors only hides it; node: the parameters node keeps it and hides the others; text narrows to it.
  await page.getByLabel('Minimum level').selectOption('error');
  await expect(mine).toHaveCount(0);
  await page.getByLabel('Minimum level').selectOption('warn');
  await expect(mine).toHaveCount(1);
  await page.getByLabel('Node').selectOption('/parameters');
  await expect(log.getByTestId('log-entry').and(page.locator(':not([data-node="/parameters"])'))).toHaveCount(0);
  await page.getByLabel('Search the log').fill(tag);
  await expect(log.getByTestId('log-entry')).toHaveCount(1);

  // The export: the filtered entries, one line each.
  const [download] = await Promise.all([page.waitForEvent('download'), page.getByRole('button', { name: 'Export' }).click()]);
  expect(download.suggestedFilename()).toMatch(/^ros-log-.*\.log$/);
  const text = fs.readFileSync(/** @type {string} */ (await download.path()), 'utf8').trim().split('\n');
  expect(text).toHaveLength(1);
  expect(text[0]).toMatch(new RegExp(`WARN /parameters .*${tag}`));

  // Opened again: the history from the robot PC has it.
  await page.reload();
  await expect(page.getByRole('list', { name: 'ROS log' }).getByTestId('log-entry').filter({ hasText: tag })).toHaveCount(1, { timeout: 15_000 });
});

test('an operator does not see the page and cannot read the log\'s history through /ros', async ({ page, context, baseURL }) => {
  await loginAs(page, 'operator');
  const pages = (await (await page.request.get('/api/config')).json()).pages.map((p) => p.id);
  expect(pages).not.toContain('inspect');
  const ros = await rosSocket(/** @type {string} */ (baseURL), await sessionCookie(context));
  try {
    ros.send({ op: 'call_service', id: 'h1', service: '/cell/inspect/log', args: { min_level: 0, node: '', text: '', max_entries: 5 } });
    const answer = await ros.waitFor((m) => m.op === 'service_response' && m.id === 'h1');
    expect(answer.result).toBe(false);
    expect(String(answer.values)).toMatch(/permission denied/);
  } finally {
    ros.ws.close();
  }
});
