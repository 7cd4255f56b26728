// The accessibility audit's shared parts: axe-core's serious and critical violations on a page, in every theme on the
// phone (the operator's device) and in the light theme elsewhere (colours are the same on every profile; what the
// layout changes, e.g. what scrolls, is not). The counts of every impact are kept and written per spec and profile.
import fs from 'node:fs';
import path from 'node:path';
import { test, expect } from '@playwright/test';
import AxeBuilder from '@axe-core/playwright';

export const PAGES = ['/', '/modules', '/process', '/manual', '/scene', '/sensors', '/video', '/parameters', '/routines', '/alarms', '/recorder', '/inspect', '/database', '/plant', '/system'];
const THEMES = ['light', 'dark', 'contrast'];
const themes = () => (test.info().project.name === 'phone' ? THEMES : ['light']);

/** @type {Record<string, Record<string, Record<string, Record<string, number>>>>} */
const results = {};

/** Writes <output dir>/<project>/a11y-<name>-<profile>.json once the spec's tests are done. @param {string} name */
export function keepResults(name) {
  test.afterAll(async ({}, info) => {
    fs.mkdirSync(info.project.outputDir, { recursive: true });
    fs.writeFileSync(path.join(info.project.outputDir, `a11y-${name}-${info.project.name}.json`), JSON.stringify(results, null, 1));
  });
}

/** @param {import('@playwright/test').Page} page @param {{theme: string, glove?: boolean}} display */
export async function useDisplay(page, display) {
  await page.addInitScript((d) => localStorage.setItem('cell-ui.display', JSON.stringify(d)), display);
}

/** Wait for the page to be drawn (its title, past the boot screen). @param {import('@playwright/test').Page} page */
export async function settle(page) {
  await expect(page.getByTestId('page-title')).toBeVisible();
}

/**
 * Every theme on one page: axe's serious and critical violations, as lines; the counts of every impact kept.
 * @param {import('@playwright/test').Page} page @param {string} url @param {string} state
 */
export async function audit(page, url, state) {
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
