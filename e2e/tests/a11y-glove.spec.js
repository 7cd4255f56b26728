// Glove mode (the display menu's choice for gloved hands): every visible control at least 64 px high.
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { settle, useDisplay } from '../lib/a11y.js';

test('glove mode makes every visible control at least 64 px high', async ({ page }) => {
  await useDisplay(page, { theme: 'system', glove: true });
  await loginAs(page, 'admin');
  for (const url of ['/', '/manual', '/process']) {
    await page.goto(url);
    await settle(page);
    const small = await page.evaluate(() => [...document.querySelectorAll('button, select, input:not([type=checkbox]):not([type=radio]):not([type=hidden]), a.btn, [role=tab]')]
      .filter((e) => {
        const r = e.getBoundingClientRect();
        return r.width > 0 && r.height > 0 && getComputedStyle(e).visibility !== 'hidden';
      })
      .filter((e) => e.getBoundingClientRect().height < 63.5)
      .map((e) => `${e.tagName.toLowerCase()} "${(e.getAttribute('aria-label') || e.textContent || '').trim().slice(0, 40)}" ${Math.round(e.getBoundingClientRect().height)} px`));
    expect(small, url).toEqual([]);
  }
});
