// The audit log on the System page (admin) on a phone: newest first, paged, filtered by user, operation and
// outcome. An operator has neither the page nor GET /api/audit.
import { test, expect } from '@playwright/test';
import { loginAs, openMenu, sessionCookie, rosSocket } from '../lib/app.js';

// (on every profile.)

test('newest first, filtered by user, operation and outcome, a page at a time', async ({ browser, page, baseURL }) => {
  test.slow();
  // Something to find: an operator's refused rosbridge publishes (each one is audited as denied).
  const opContext = await browser.newContext({ baseURL });
  const opPage = await opContext.newPage();
  await loginAs(opPage, 'operator');
  const ros = await rosSocket(/** @type {string} */ (baseURL), await sessionCookie(opContext));
  const N = 30;
  for (let i = 0; i < N; i++) ros.send({ op: 'publish', id: `audit-${i}`, topic: '/cell/mode', msg: { mode: 'running', source: `e2e ${i}` } });
  await ros.waitFor((m) => m.op === 'status' && m.id === `audit-${N - 1}`);
  ros.ws.close();
  await opContext.close();

  await loginAs(page, 'admin');
  await openMenu(page);
  await page.getByTestId('nav-system').click();
  const audit = page.getByTestId('audit');
  await expect(audit.getByRole('heading', { name: 'Audit log' })).toBeVisible();
  // Newest first: times never increase down the list, and the admin's own login comes before the operator's.
  await expect(audit.getByTestId('audit-entry').first()).toBeVisible();
  const times = await audit.getByTestId('audit-entry').evaluateAll((els) => els.map((e) => e.getAttribute('data-time') ?? ''));
  expect(times.length).toBeGreaterThan(1);
  expect([...times].sort().reverse()).toEqual(times);
  const users = await audit.getByTestId('audit-entry').evaluateAll((els) => els.map((e) => e.getAttribute('data-user')));
  const ops = await audit.getByTestId('audit-entry').evaluateAll((els) => els.map((e) => e.getAttribute('data-op')));
  const adminLogin = users.findIndex((u, i) => u === 'admin' && ops[i] === 'login');
  expect(adminLogin).toBeGreaterThanOrEqual(0);
  expect(adminLogin).toBeLessThan(users.indexOf('operator'));

  await audit.getByRole('combobox', { name: 'Filter by user' }).fill('operator');
  await audit.getByRole('combobox', { name: 'Filter by operation' }).fill('ros.publish');
  await audit.getByRole('combobox', { name: 'Filter by outcome' }).selectOption('denied');
  await audit.getByRole('button', { name: 'Apply filters' }).click();
  const position = audit.getByTestId('audit-position');
  await expect(position).toContainText(/^1–25 of \d+, newest first/);
  await expect(position).toContainText('filtered');
  const total = Number((await position.textContent())?.match(/of (\d+)/)?.[1]);
  expect(total).toBeGreaterThanOrEqual(N);
  const entries = audit.getByTestId('audit-entry');
  await expect(entries).toHaveCount(25);
  for (const e of await entries.all()) {
    await expect(e).toHaveAttribute('data-user', 'operator');
    await expect(e).toHaveAttribute('data-op', 'ros.publish');
    await expect(e).toContainText('Denied');
  }
  // The newest of them is the last one sent.
  await expect(entries.first()).toContainText('/cell/mode');

  await audit.getByRole('button', { name: 'Older entries' }).click();
  await expect(position).toContainText(`26–${Math.min(50, total)} of ${total}`);
  await expect(audit.getByRole('button', { name: 'Newer entries' })).toBeEnabled();
  await audit.getByRole('button', { name: 'Newer entries' }).click();
  await expect(position).toContainText(`1–25 of ${total}`);

  await audit.getByRole('button', { name: 'Clear filters' }).click();
  await expect(position).not.toContainText('filtered');
  await expect(audit.getByTestId('audit-entry').first()).toHaveAttribute('data-user', 'admin');
  // (the admin's own login or what its pages did since)
});

test('an operator cannot open the audit log nor its API', async ({ page }) => {
  await loginAs(page, 'operator');
  expect((await page.request.get('/api/audit')).status()).toBe(403);
  expect((await page.request.get('/api/audit?user=admin&limit=5')).status()).toBe(403);
  await openMenu(page);
  await expect(page.getByTestId('nav-system')).toHaveCount(0);
  await page.goto('/system');
  await expect(page.getByTestId('access-denied')).toBeVisible();
  await expect(page.getByTestId('audit')).toHaveCount(0);
});
