// UI steps shared by the specs (data-testid contract of app/).
import { expect } from '@playwright/test';
import { WebSocket } from 'ws';

export const users = () => JSON.parse(process.env.E2E_USERS);

/**
 * @param {import('@playwright/test').Page} page @param {string} who a role of the cell file (its user is named after it)
 * @param {string} [next] the page to land on after signing in (default Home)
 */
export async function loginAs(page, who, next = '') {
  await page.goto(next ? `/login?next=${encodeURIComponent(next)}` : '/login');
  await page.getByTestId('login-username').fill(who);
  await page.getByTestId('login-password').fill(users()[who]);
  await page.getByTestId('login-submit').click();
  await expect(page).not.toHaveURL(/\/login/);
  if (next) await expect(page).toHaveURL((url) => url.pathname === next);
  await expect(page.getByTestId('page-title')).toBeVisible();
}

/**
 * On a phone the side menu is a drawer: open it. From 768 px (tablet, desktop) the menu is always on screen and
 * the toggle is hidden by CSS; the viewport decides, not the toggle's visibility at one moment (CI: a toggle seen
 * as visible on desktop before the layout's styles applied, then hidden under the click).
 * @param {import('@playwright/test').Page} page
 */
export async function openMenu(page) {
  const toggle = page.getByTestId('menu-toggle');
  if ((page.viewportSize()?.width ?? 0) >= 768) {
    await expect(toggle).toBeHidden();
  } else {
    await toggle.click();
  }
  await expect(page.getByTestId('user-name')).toBeVisible();
}

/**
 * In-app navigation through the menu (what lives in the app, like a routine draft, stays), to the page `title`.
 * @param {import('@playwright/test').Page} page @param {string} title the page's title in the cell file
 */
export async function goToPage(page, title) {
  await openMenu(page);
  await page.getByRole('navigation', { name: 'Main menu' }).getByRole('link', { name: title, exact: true }).click();
  await expect(page.getByTestId('page-title')).toHaveText(title);
}

/** @param {import('@playwright/test').BrowserContext} context */
export async function sessionCookie(context) {
  return (await context.cookies()).find((c) => c.name === 'cell_session');
}

/** A rosbridge client on /ros with the browser's session cookie. */
export async function rosSocket(baseURL, cookie) {
  const ws = new WebSocket(`${baseURL.replace('http', 'ws')}/ros`, { headers: { cookie: `cell_session=${cookie.value}` } });
  const inbox = [];
  ws.on('message', (d) => inbox.push(JSON.parse(d.toString())));
  await new Promise((resolve, reject) => { ws.once('open', resolve); ws.once('error', reject); });
  const send = (m) => ws.send(JSON.stringify(m));
  const waitFor = async (pred) => {
    await expect.poll(() => inbox.find(pred), { timeout: 10_000 }).toBeTruthy();
    return inbox.find(pred);
  };
  return { ws, inbox, send, waitFor };
}
