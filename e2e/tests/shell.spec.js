// The walking skeleton, end to end: login, roles, live mode from ROS, reconnect, offline shell, logout.
import { test, expect } from '@playwright/test';
import { WebSocket } from 'ws';
import { loginAs, openMenu, sessionCookie, users } from '../lib/app.js';
import { publishMode, nodePid } from '../lib/ros.js';

test('a wrong password shows an error and opens no session', async ({ page, context }) => {
  await page.goto('/');
  await expect(page).toHaveURL(/\/login/);
  await page.getByTestId('login-username').fill('operator');
  await page.getByTestId('login-password').fill('wrong-password');
  await page.getByTestId('login-submit').click();
  await expect(page.getByTestId('login-error')).toBeVisible();
  expect(await sessionCookie(context)).toBeUndefined();
  expect((await page.request.get('/api/auth/me')).status()).toBe(401);
  await expect(page).toHaveURL(/\/login/);
});

test('an operator sees only operator pages; the admin page is refused in the app and by the server', async ({ page }) => {
  await loginAs(page, 'operator');
  await openMenu(page);
  await expect(page.getByTestId('user-name')).toHaveText('operator');
  await expect(page.getByTestId('user-role')).toContainText('operator');
  await expect(page.getByTestId('nav-home')).toBeVisible();
  await expect(page.getByTestId('nav-system')).toHaveCount(0);

  await page.goto('/system');
  await expect(page.getByTestId('access-denied')).toBeVisible();
  await expect(page.getByTestId('system-users')).toHaveCount(0);
  expect((await page.request.get('/api/system')).status()).toBe(403);
});

test('an admin sees the System page with the users and their roles', async ({ page }) => {
  await loginAs(page, 'admin');
  await openMenu(page);
  await page.getByTestId('nav-system').click();
  await expect(page).toHaveURL(/\/system$/);
  await expect(page.getByTestId('page-title')).toHaveText(/System/);
  const table = page.getByTestId('system-users');
  await expect(table).toContainText('admin');
  await expect(table).toContainText('operator');
  await expect(page.getByTestId('system-cell-file')).toContainText('demo-cell.yaml');
  await expect(page.getByTestId('system-health')).toBeVisible();
});

test('the operation mode published from ROS appears live in the side menu', async ({ page }) => {
  await loginAs(page, 'operator');
  await openMenu(page);
  await expect(page.getByTestId('conn-status')).toHaveText('connected');
  await publishMode('programming');
  await expect(page.getByTestId('op-mode')).toHaveText('programming');
  await publishMode('manual');
  await expect(page.getByTestId('op-mode')).toHaveText('manual');
  await expect(page.getByTestId('home-mode')).toContainText('manual');
});

test('killing rosbridge shows reconnecting; when it is back the app reconnects and updates without a reload', async ({ page }) => {
  await loginAs(page, 'admin');
  await openMenu(page);
  await expect(page.getByTestId('conn-status')).toHaveText('connected');
  await publishMode('idle');
  await expect(page.getByTestId('op-mode')).toHaveText('idle');
  const pid = await nodePid('/rosbridge_websocket');
  expect(pid).toBeGreaterThan(0);
  const navigations = [];
  page.on('framenavigated', (f) => { if (f === page.mainFrame()) navigations.push(f.url()); });
  process.kill(pid, 'SIGKILL');
  await expect(page.getByTestId('conn-status')).toHaveText('reconnecting');
  // roslaunch respawns rosbridge; the app's backoff reconnects and restores its subscriptions.
  await expect(page.getByTestId('conn-status')).toHaveText('connected', { timeout: 30_000 });
  await expect.poll(() => nodePid('/rosbridge_websocket'), { timeout: 15_000 }).not.toBe(pid);
  await publishMode('paused');
  await expect(page.getByTestId('op-mode')).toHaveText('paused');
  expect(navigations).toEqual([]);
});

test('after one online visit, an offline reload shows the shell with the offline notice', async ({ page, context }) => {
  await loginAs(page, 'operator');
  await page.evaluate(async () => {
    await navigator.serviceWorker.ready;
  });
  // The page is controlled by the service worker once it claims clients.
  await expect.poll(() => page.evaluate(() => !!navigator.serviceWorker.controller)).toBe(true);
  await expect(page.getByTestId('offline-notice')).toHaveCount(0);
  await context.setOffline(true);
  await page.reload();
  await expect(page.getByTestId('offline-notice')).toBeVisible();
  await expect(page.getByTestId('offline-notice')).toContainText('Offline');
  await expect(page.getByTestId('page-title')).toBeVisible();
  await context.setOffline(false);
  await expect(page.getByTestId('offline-notice')).toHaveCount(0);
});

test('logout ends the session: the old cookie no longer opens /ros or the API', async ({ page, context, baseURL }) => {
  await loginAs(page, 'operator');
  const cookie = await sessionCookie(context);
  expect(cookie.httpOnly).toBe(true);
  expect(cookie.sameSite).toBe('Strict');
  const header = `cell_session=${cookie.value}`;
  const wsUrl = `${baseURL.replace('http', 'ws')}/ros`;
  const upgrade = () => new Promise((resolve) => {
    const ws = new WebSocket(wsUrl, { headers: { cookie: header } });
    ws.on('open', () => { ws.close(); resolve(101); });
    ws.on('unexpected-response', (_q, res) => resolve(res.statusCode));
    ws.on('error', () => {});
  });
  expect(await upgrade()).toBe(101);

  await openMenu(page);
  await page.getByTestId('logout').click();
  await expect(page).toHaveURL(/\/login/);
  expect(await upgrade()).toBe(401);
  const me = await fetch(`${baseURL}/api/auth/me`, { headers: { cookie: header } });
  expect(me.status).toBe(401);
  expect(users().operator).toBeTruthy();
});

test('the certificate trust page comes from the server even once the service worker is active', async ({ page }) => {
  await loginAs(page, 'operator');
  await expect.poll(() => page.evaluate(() => !!navigator.serviceWorker.controller)).toBe(true);
  await page.goto('/trust');
  await expect(page.locator('a[href="/ca.crt"]').first()).toBeVisible();
  await expect(page.locator('svg').first()).toBeVisible();
  await expect(page.getByTestId('not-found')).toHaveCount(0);
});

test('the login page comes with its own modules preloaded: no route module waits for the app to start', async ({ page }) => {
  /** @type {string[]} */
  const nodes = [];
  page.on('request', (r) => {
    const p = new URL(r.url()).pathname;
    if (p.startsWith('/_app/immutable/nodes/')) nodes.push(p);
  });
  const res = await page.goto('/login');
  await expect(page.getByTestId('login-username')).toBeEditable();
  // The page as served (once running, Vite's loader adds preload links of its own for what it imports).
  const served = [...(await res.text()).matchAll(/<link href="([^"]+)" rel="modulepreload">/g)].map((m) => m[1]);
  // The root layout, the root error page and the login page: SvelteKit's fallback preloads only the first.
  expect(nodes.length).toBeGreaterThanOrEqual(3);
  expect(nodes.filter((n) => !served.includes(n))).toEqual([]);
});
