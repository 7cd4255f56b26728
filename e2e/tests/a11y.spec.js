// Accessibility audit with axe-core on every page of the cell, in every theme (light, dark, high contrast; on the phone)
// and in glove mode, as the admin (who sees every page) with the live stack behind it: no serious or critical violation.
// Glove mode: every visible control at least 64 px high. The results per page are written to
// test-results/a11y-<profile>.json (the counts of every impact, for the record).
import fs from 'node:fs';
import path from 'node:path';
import { test, expect } from '@playwright/test';
import AxeBuilder from '@axe-core/playwright';
import { loginAs } from '../lib/app.js';
import { simFault, clearSimFault, recorderIdle } from '../lib/ros.js';

const PAGES = ['/', '/modules', '/process', '/manual', '/scene', '/sensors', '/video', '/parameters', '/routines', '/alarms', '/recorder', '/inspect', '/database', '/plant', '/system'];
const THEMES = ['light', 'dark', 'contrast'];
// Every theme on the phone (the operator's device); the tablet's and desktop's layouts in the light theme only, to keep
// the suite's time (colours are the same on every profile; what the layout changes, e.g. what scrolls, is not).
const themes = () => (test.info().project.name === 'phone' ? THEMES : ['light']);

/** @type {Record<string, Record<string, Record<string, Record<string, number>>>>} */
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

/**
 * Every theme on one page: axe's serious and critical violations, as lines; the counts of every impact kept.
 * @param {import('@playwright/test').Page} page @param {string} url @param {string} state
 */
async function audit(page, url, state) {
  await page.goto(url);
  await settle(page);
  /** @type {string[]} */
  const problems = [];
  for (const theme of themes()) {
    // What the menu's Theme choice does: the root's data-theme, drawn at once.
    await page.evaluate((t) => { document.documentElement.dataset.theme = t; }, theme);
    const r = await new AxeBuilder({ page }).withTags(['wcag2a', 'wcag2aa', 'wcag21a', 'wcag21aa']).analyze();
    const counts = /** @type {Record<string, number>} */ ({});
    for (const v of r.violations) counts[v.impact ?? 'unknown'] = (counts[v.impact ?? 'unknown'] ?? 0) + v.nodes.length;
    ((results[state] ??= {})[theme] ??= {})[url] = counts;
    for (const v of r.violations.filter((x) => x.impact === 'serious' || x.impact === 'critical')) {
      problems.push(`${url} [${theme}, ${state}] ${v.id} (${v.impact}): ${v.help} -> ${v.nodes.slice(0, 3).map((n) => `${n.target.join(' ')} ${n.any?.[0]?.message ?? ''}`).join(' | ')}`);
    }
  }
  return problems;
}

test('every page in every theme has no serious or critical accessibility violation', async ({ page }) => {
  // 15 pages x 3 themes of axe on a loaded machine.
  test.setTimeout(300_000);
  await useDisplay(page, { theme: 'light', glove: false });
  await loginAs(page, 'admin');
  /** @type {string[]} */
  const problems = [];
  for (const url of PAGES) problems.push(...(await audit(page, url, 'calm')));
  expect(problems).toEqual([]);
});

test('with an active alarm (its banner, red badges, the Alarms page) every theme has no serious or critical violation', async ({ page }) => {
  test.setTimeout(180_000);
  await loginAs(page, 'admin');
  await simFault('gripper_fault');
  try {
    await page.goto('/alarms');
    await expect(page.locator('[data-testid="alarm"][data-alarm="device.gripper_fault"][data-active="true"]')).toBeVisible({ timeout: 20_000 });
    /** @type {string[]} */
    const problems = [];
    for (const url of ['/', '/alarms', '/process', '/manual', '/modules']) problems.push(...(await audit(page, url, 'alarm')));
    expect(problems).toEqual([]);
  } finally {
    await clearSimFault();
    await recorderIdle();
  }
});

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
