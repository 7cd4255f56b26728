// Accessibility audit with axe-core on every page of the cell, in every theme (light, dark, high contrast) and in
// glove mode, as the admin (who sees every page) with the live stack behind it: no serious or critical violation.
// Glove mode: every visible control at least 64 px high. The results per page are written to
// test-results/a11y-<profile>.json (the counts of every impact, for the record).
import fs from 'node:fs';
import path from 'node:path';
import { test, expect } from '@playwright/test';
import AxeBuilder from '@axe-core/playwright';
import { loginAs } from '../lib/app.js';

const PAGES = ['/', '/modules', '/process', '/manual', '/scene', '/sensors', '/video', '/parameters', '/routines', '/alarms', '/recorder', '/inspect', '/database', '/plant', '/system'];
const THEMES = ['light', 'dark', 'contrast'];

/** @type {Record<string, Record<string, Record<string, number>>>} */
const results = {};

test.afterAll(async ({}, info) => {
  fs.mkdirSync(info.project.outputDir, { recursive: true });
  fs.writeFileSync(path.join(info.project.outputDir, `a11y-${info.project.name}.json`), JSON.stringify(results, null, 1));
});

/** @param {import('@playwright/test').Page} page @param {{theme: string, glove?: boolean}} display */
async function useDisplay(page, display) {
  await page.addInitScript((d) => localStorage.setItem('cell-ui.display', JSON.stringify(d)), display);
}

/** Wait for the page to be drawn (its title, past the boot screen). @param {import('@playwright/test').Page} page */
async function settle(page) {
  await expect(page.getByTestId('page-title')).toBeVisible();
}

for (const theme of THEMES) {
  test(`every page in the ${theme} theme has no serious or critical accessibility violation`, async ({ page }) => {
    test.slow();
    await useDisplay(page, { theme, glove: false });
    await loginAs(page, 'admin');
    await expect(page.locator('html')).toHaveAttribute('data-theme', theme);
    /** @type {string[]} */
    const problems = [];
    for (const url of PAGES) {
      await page.goto(url);
      await settle(page);
      const r = await new AxeBuilder({ page }).withTags(['wcag2a', 'wcag2aa', 'wcag21a', 'wcag21aa']).analyze();
      const counts = /** @type {Record<string, number>} */ ({});
      for (const v of r.violations) counts[v.impact ?? 'unknown'] = (counts[v.impact ?? 'unknown'] ?? 0) + v.nodes.length;
      (results[theme] ??= {})[url] = counts;
      for (const v of r.violations.filter((x) => x.impact === 'serious' || x.impact === 'critical')) {
        problems.push(`${url} [${theme}] ${v.id} (${v.impact}): ${v.help} -> ${v.nodes.slice(0, 3).map((n) => n.target.join(' ')).join(' | ')}`);
      }
    }
    expect(problems).toEqual([]);
  });
}

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
