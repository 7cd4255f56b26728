// Every page's layout on this profile (run on the phone, the tablet and the desktop: what differs between them is
// the layout, so each behaviour's spec runs on one profile and this one on all three; playwright.config.js).
// As the admin, who sees every page: nothing wider than the screen (no sideways scrolling of the page), every
// control inside the screen's width or inside a box that scrolls sideways on purpose, every control at least
// 24 x 24 CSS px (WCAG 2.2 target size, minimum), and on touch screens the menu opens and leads to the page.
import { test, expect } from '@playwright/test';
import { loginAs, openMenu } from '../lib/app.js';
import { PAGES, settle } from '../lib/a11y.js';

const CONTROLS = 'button, select, input:not([type=hidden]), textarea, a[href], [role=button], [role=tab], [role=switch], [role=slider]';

/** @param {import('@playwright/test').Page} page */
function layoutProblems(page) {
  return page.evaluate((selector) => {
    const out = [];
    const width = document.documentElement.clientWidth;
    const sideways = document.scrollingElement?.scrollWidth ?? 0;
    if (sideways > width + 1) out.push(`the page scrolls sideways: ${sideways} px wide on a ${width} px screen`);
    /** A box between the control and the page that scrolls sideways on purpose (a wide table, a strip of tabs). */
    const scrolledBy = (/** @type {Element} */ e) => {
      for (let p = e.parentElement; p && p !== document.body; p = p.parentElement) {
        const ox = getComputedStyle(p).overflowX;
        if ((ox === 'auto' || ox === 'scroll') && p.scrollWidth > p.clientWidth) return true;
      }
      return false;
    };
    /** Link text inside a sentence is exempt from the target size (WCAG 2.5.8, "inline"). */
    const inline = (/** @type {Element} */ e) => e.tagName === 'A' && getComputedStyle(e).display === 'inline';
    for (const e of document.querySelectorAll(selector)) {
      const r = e.getBoundingClientRect();
      const style = getComputedStyle(e);
      if (r.width === 0 || r.height === 0 || style.visibility === 'hidden' || e.closest('[inert], [aria-hidden=true]')) continue;
      const name = `${e.tagName.toLowerCase()} "${(e.getAttribute('aria-label') || e.textContent || e.getAttribute('name') || '').trim().replace(/\s+/g, ' ').slice(0, 40)}"`;
      if ((r.left < -1 || r.right > width + 1) && !scrolledBy(e)) out.push(`${name} sticks out of the screen (${Math.round(r.left)}..${Math.round(r.right)} of ${width} px)`);
      // A checkbox or radio's target is its label too (a tap on the label sets it).
      const box = /** @type {HTMLInputElement} */ (e);
      const label = box.type === 'checkbox' || box.type === 'radio' ? box.labels?.[0] : undefined;
      const t = label ? label.getBoundingClientRect() : r;
      if (!inline(e) && (t.width < 23.5 || t.height < 23.5)) out.push(`${name} is ${Math.round(t.width)} x ${Math.round(t.height)} px (at least 24 x 24)`);
    }
    return out;
  }, CONTROLS);
}

test('every page fits the screen: no sideways scrolling, every control on screen and at least 24 x 24 px', async ({ page }) => {
  test.setTimeout(120_000);
  await loginAs(page, 'admin');
  /** @type {string[]} */
  const problems = [];
  for (const url of PAGES) {
    await page.goto(url);
    await settle(page);
    problems.push(...(await layoutProblems(page)).map((p) => `${url}: ${p}`));
  }
  expect(problems).toEqual([]);
});

test('the menu reaches every page from this screen, and the page it opens fits it', async ({ page }) => {
  await loginAs(page, 'admin');
  await openMenu(page);
  const menu = page.getByRole('navigation', { name: 'Main menu' });
  const links = await menu.getByRole('link').evaluateAll((as) => as.map((a) => new URL(/** @type {HTMLAnchorElement} */ (a).href).pathname));
  expect([...links].sort()).toEqual([...PAGES].sort());
  // The last entry: on a phone the drawer scrolls to it; the tap lands and the drawer closes over the new page.
  const last = menu.getByRole('link').last();
  await last.scrollIntoViewIfNeeded();
  await last.click();
  await expect(page).toHaveURL((url) => url.pathname === links.at(-1));
  await settle(page);
  // A phone's drawer closes over the new page (the menu is always on screen from 768 px).
  if ((page.viewportSize()?.width ?? 0) < 768) await expect(page.getByTestId('user-name')).toBeHidden();
  expect(await layoutProblems(page)).toEqual([]);
});
