// UI steps shared by the specs (data-testid contract of app/).
import { expect } from '@playwright/test';

export const users = () => JSON.parse(process.env.E2E_USERS);

/** @param {import('@playwright/test').Page} page @param {'admin'|'operator'} who */
export async function loginAs(page, who) {
  await page.goto('/login');
  await page.getByTestId('login-username').fill(who);
  await page.getByTestId('login-password').fill(users()[who]);
  await page.getByTestId('login-submit').click();
  await expect(page).not.toHaveURL(/\/login/);
  await expect(page.getByTestId('page-title')).toBeVisible();
}

/** On a phone the side menu is a drawer: open it when its toggle is shown. @param {import('@playwright/test').Page} page */
export async function openMenu(page) {
  const toggle = page.getByTestId('menu-toggle');
  if (await toggle.isVisible()) {
    await toggle.click();
  }
  await expect(page.getByTestId('user-name')).toBeVisible();
}

/** @param {import('@playwright/test').BrowserContext} context */
export async function sessionCookie(context) {
  return (await context.cookies()).find((c) => c.name === 'cell_session');
}
