// Sensors on a phone: the cell file's graphs draw live data (the simulated wrist F/T sensor and tactile pad),
// Pause/Resume per graph, and the page holds rosbridge subscriptions only while it is shown and visible: the
// rosbridge node leaves the topic's subscribers when the app is hidden or the page is left (rostopic info).
import { test, expect } from '@playwright/test';
import { loginAs, openMenu } from '../lib/app.js';
import { rosCli } from '../lib/ros.js';

// (on every profile, the rostopic checks and the hidden-page check included.)

const ROSBRIDGE = '/rosbridge_websocket';

/** The nodes subscribed to a topic, as `rostopic info` lists them. @param {string} topic */
async function subscribers(topic) {
  const { stdout } = await rosCli(`rostopic info ${topic}`);
  const section = stdout.split(/Subscribers:/)[1] ?? '';
  return [...section.matchAll(/\*\s+(\S+)/g)].map((m) => m[1]);
}

/** @param {import('@playwright/test').Page} page @param {'hidden' | 'visible'} state */
async function setVisibility(page, state) {
  await page.evaluate((s) => {
    Object.defineProperty(document, 'visibilityState', { value: s, configurable: true });
    Object.defineProperty(document, 'hidden', { value: s === 'hidden', configurable: true });
    document.dispatchEvent(new Event('visibilitychange'));
  }, state);
}

/** How many times a graph has been drawn (the plot's data-draws). @param {import('@playwright/test').Locator} graph */
const draws = async (graph) => Number((await graph.getByTestId('sensor-plot').getAttribute('data-draws')) ?? 0);

test('live graphs from the cell file, with legend, values and Pause / Resume per graph', async ({ page }) => {
  await loginAs(page, 'operator');
  await openMenu(page);
  await page.getByTestId('nav-sensors').click();
  await expect(page).toHaveURL(/\/sensors$/);

  const wrench = page.getByTestId('sensor-graph').filter({ has: page.getByRole('heading', { name: 'Wrist wrench' }) });
  const tactile = page.getByTestId('sensor-graph').filter({ has: page.getByRole('heading', { name: 'Tactile pad' }) });
  await expect(wrench.getByRole('img', { name: /Wrist wrench: Fx, Fy, Fz, Tx, Ty, Tz over the last 10 s/ })).toBeVisible();
  const legend = wrench.getByRole('list', { name: 'Wrist wrench legend and latest values' });
  for (const l of ['Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz']) await expect(legend).toContainText(l);
  await expect(wrench.getByTestId('sensor-freshness-age')).toHaveText(/updated/);
  await expect.poll(() => draws(wrench)).toBeGreaterThan(10);
  await expect(tactile.getByTestId('sensor-scatter-count')).toHaveText(/\d+ points/);

  // Drawing keeps to the animation frames: over two seconds, no more draws than frames (the wrench arrives faster
  // than the frames come), and at least one (live). How many frames come depends on the host's load (CI: 5).
  const before = await draws(wrench);
  const frames = await page.evaluate(() => new Promise((resolve) => {
    let n = 0;
    const t0 = performance.now();
    const tick = () => (performance.now() - t0 < 2000 ? (n++, requestAnimationFrame(tick)) : resolve(n));
    requestAnimationFrame(tick);
  }));
  const drawn = (await draws(wrench)) - before;
  expect(drawn).toBeGreaterThan(0);
  expect(drawn).toBeLessThanOrEqual(Number(frames) + 2);

  // Pause freezes this graph only.
  await wrench.getByRole('button', { name: 'Pause Wrist wrench' }).click();
  const resume = wrench.getByRole('button', { name: 'Resume Wrist wrench' });
  await expect(resume).toHaveAttribute('aria-pressed', 'true');
  await expect(wrench.getByTestId('sensor-paused')).toHaveText('Paused');
  const frozen = await draws(wrench);
  const tactileBefore = await draws(tactile);
  await page.waitForTimeout(1000);
  expect(await draws(wrench)).toBe(frozen);
  expect(await draws(tactile)).toBeGreaterThan(tactileBefore);
  await resume.click();
  await expect(wrench.getByRole('button', { name: 'Pause Wrist wrench' })).toBeVisible();
  await expect.poll(() => draws(wrench)).toBeGreaterThan(frozen);
});

test('subscribed only while shown and visible: rosbridge leaves the topic when the app is hidden or the page is left', async ({ page }) => {
  test.slow();
  await loginAs(page, 'operator', '/sensors');
  const wrench = page.getByTestId('sensor-graph').filter({ has: page.getByRole('heading', { name: 'Wrist wrench' }) });
  await expect.poll(() => draws(wrench)).toBeGreaterThan(0);
  await expect.poll(() => subscribers('/cell/wrench'), { timeout: 15_000 }).toContain(ROSBRIDGE);
  await expect.poll(() => subscribers('/cell/tactile'), { timeout: 15_000 }).toContain(ROSBRIDGE);

  await setVisibility(page, 'hidden');
  await expect(page.getByText(/Paused while the app is hidden/)).toBeVisible();
  await expect.poll(() => subscribers('/cell/wrench'), { timeout: 15_000 }).not.toContain(ROSBRIDGE);
  await expect.poll(() => subscribers('/cell/tactile'), { timeout: 15_000 }).not.toContain(ROSBRIDGE);
  // Nothing is drawn while hidden.
  const hiddenDraws = await draws(wrench);
  await page.waitForTimeout(500);
  expect(await draws(wrench)).toBe(hiddenDraws);

  await setVisibility(page, 'visible');
  await expect.poll(() => subscribers('/cell/wrench'), { timeout: 15_000 }).toContain(ROSBRIDGE);
  await expect.poll(() => draws(wrench)).toBeGreaterThan(hiddenDraws);

  await openMenu(page);
  await page.getByTestId('nav-alarms').click();
  await expect(page).toHaveURL(/\/alarms$/);
  await expect.poll(() => subscribers('/cell/wrench'), { timeout: 15_000 }).not.toContain(ROSBRIDGE);
  await expect.poll(() => subscribers('/cell/tactile'), { timeout: 15_000 }).not.toContain(ROSBRIDGE);
});
