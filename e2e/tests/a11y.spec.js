// Accessibility audit with axe-core on every page of the cell (lib/a11y.js: every theme on the phone, the light theme
// elsewhere), as the admin (who sees every page) with the live stack behind it: no serious or critical violation.
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { PAGES, audit, keepResults, useDisplay } from '../lib/a11y.js';

keepResults('calm');

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
