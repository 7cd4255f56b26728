// The Recordings page as the recorder specs read it (demo and iiwa cells).
import { expect } from '@playwright/test';

export const MCAP_MAGIC = Buffer.from([0x89, 0x4d, 0x43, 0x41, 0x50, 0x30, 0x0d, 0x0a]);

/** The names listed, once the list has loaded. @param {import('@playwright/test').Page} page */
export async function listed(page) {
  await expect(page.getByRole('list', { name: 'Recordings' }).or(page.getByTestId('recordings-empty'))).toBeVisible();
  return page.getByTestId('recording').evaluateAll((els) => els.map((e) => e.getAttribute('data-name')));
}

/** The one recording listed that was not before. @param {import('@playwright/test').Page} page @param {(string|null)[]} before */
export async function newRecording(page, before) {
  let name = '';
  await expect.poll(async () => {
    const fresh = (await page.getByTestId('recording').evaluateAll((els) => els.map((e) => e.getAttribute('data-name'))))
      .filter((n) => !before.includes(n));
    name = fresh[0] ?? '';
    return fresh.length;
  }, { timeout: 40_000, message: 'a new recording in the list' }).toBe(1);
  return page.locator(`[data-testid="recording"][data-name="${name}"]`);
}
