// A raw camera (sensor_msgs/Image, 1280x720 from the sim, as usb_cam or a GigE driver publishes): the viewer asks
// the video node for JPEG at its element's width in device pixels and gets frames of that size; full screen asks
// for a larger size (desktop) and never a smaller one; the browser never subscribes the raw topic (the video node
// does, only while watched: checked with the master's state); leaving the page ends it.
import { test, expect } from '@playwright/test';
import { loginAs } from '../lib/app.js';
import { rosCli } from '../lib/ros.js';

const RAW = '/cell/camera/global/image_raw';
const NAME = 'Global 720p raw';
const SOURCE_WIDTH = 1280;

/** @param {string} topic */
async function subscribers(topic) {
  const { stdout } = await rosCli(`rostopic info ${topic}`);
  const section = stdout.split(/Subscribers:/)[1] ?? '';
  return [...section.matchAll(/\*\s+(\S+)/g)].map((m) => m[1]);
}

/** The width the viewer should ask for: its element in device pixels, rounded up to 160 px. @param {import('@playwright/test').Page} page */
const expectedWidth = (page) => page.getByTestId('video-frame').evaluate((el) => Math.max(160, Math.ceil(Math.ceil(el.clientWidth * devicePixelRatio) / 160) * 160));

test('a raw 720p camera reaches the viewer as JPEG at its element size; full screen asks for more; only the video node subscribes the raw topic, while watched', async ({ page }) => {
  test.slow();
  // What the browser asks rosbridge to subscribe to.
  /** @type {string[]} */
  const subscribed = [];
  page.on('websocket', (ws) => ws.on('framesent', (f) => {
    try {
      const m = JSON.parse(String(f.payload));
      if (m.op === 'subscribe') subscribed.push(m.topic);
    } catch { /* not JSON */ }
  }));
  await loginAs(page, 'operator', '/video');
  await page.getByRole('radio', { name: NAME }).check();
  const camera = page.getByTestId('video');
  await expect(camera).toHaveAttribute('data-type', 'raw');
  await expect(page.getByRole('img', { name: `${NAME} camera image` })).toBeVisible({ timeout: 30_000 });
  await expect(page.getByTestId('video-badge')).toHaveText('Live', { timeout: 15_000 });

  const asked = await expectedWidth(page);
  await expect(camera).toHaveAttribute('data-request-width', String(asked));
  const canvas = page.getByRole('img', { name: `${NAME} camera image` }).locator('canvas');
  // The frames are the size asked for (never larger than the camera's 1280), 16:9 as the camera's.
  await expect.poll(() => canvas.evaluate((c) => /** @type {HTMLCanvasElement} */ (c).width), { timeout: 15_000 }).toBe(Math.min(asked, SOURCE_WIDTH));
  const h = await canvas.evaluate((c) => /** @type {HTMLCanvasElement} */ (c).height);
  expect(Math.abs(h - Math.min(asked, SOURCE_WIDTH) * 720 / 1280)).toBeLessThanOrEqual(1);
  await expect(camera).toHaveAttribute('data-source-topic', /^\/cell\/video\/cell_camera_global_image_raw\/(w\d+|full)_q70$/);

  await expect.poll(() => subscribers(RAW), { timeout: 15_000 }).toEqual(['/video']);
  expect(subscribed).toContain(await camera.getAttribute('data-source-topic'));
  expect(subscribed).not.toContain(RAW);

  await page.getByRole('button', { name: 'Full screen' }).click();
  await expect(page.getByRole('button', { name: 'Exit full screen' })).toHaveAttribute('aria-pressed', 'true');
  const full = await expectedWidth(page);
  expect(full).toBeGreaterThanOrEqual(asked);
  await expect(camera).toHaveAttribute('data-request-width', String(full), { timeout: 10_000 });
  await expect.poll(() => canvas.evaluate((c) => /** @type {HTMLCanvasElement} */ (c).width), { timeout: 15_000 }).toBe(Math.min(full, SOURCE_WIDTH));
  if (test.info().project.name === 'desktop') expect(full).toBeGreaterThan(asked);
  await page.getByRole('button', { name: 'Exit full screen' }).click();

  // Leaving the page: the viewer leaves the output, and the video node the camera.
  await page.goto('/');
  await expect.poll(() => subscribers(RAW), { timeout: 15_000 }).toEqual([]);
});

test('on a link too slow for the camera\'s frames the viewer asks smaller ones (lower quality first) and keeps showing live frames', async ({ page, context }) => {
  test.slow();
  await loginAs(page, 'operator', '/video');
  await page.getByRole('radio', { name: NAME }).check();
  const camera = page.getByTestId('video');
  await expect(page.getByTestId('video-badge')).toHaveText('Live', { timeout: 30_000 });
  await expect(camera).toHaveAttribute('data-link-level', '0');
  await expect(camera).toHaveAttribute('data-request-quality', '70');
  await expect(page.getByTestId('video-link')).toHaveCount(0);
  const width = Number(await camera.getAttribute('data-request-width'));

  // Chromium's network emulation: 40 KB/s down, far less than the camera's frames at this size.
  const cdp = await context.newCDPSession(page);
  await cdp.send('Network.enable');
  await cdp.send('Network.emulateNetworkConditions', { offline: false, latency: 20, downloadThroughput: 40_000, uploadThroughput: 200_000 });
  await expect(camera).toHaveAttribute('data-request-quality', '50', { timeout: 20_000 });
  await expect(camera).toHaveAttribute('data-request-width', String(width));
  await expect(camera).toHaveAttribute('data-source-topic', /_q50$/, { timeout: 10_000 });
  await expect(page.getByTestId('video-link')).toHaveText('Smaller frames for a slow link');
  // Still short: next the quality floor, then half the width.
  await expect(camera).toHaveAttribute('data-request-quality', '30', { timeout: 20_000 });
  await expect.poll(async () => Number(await camera.getAttribute('data-request-width')), { timeout: 20_000 }).toBeLessThan(width);
  await expect(camera).toHaveAttribute('data-source-topic', /\/w\d+_q30$/, { timeout: 10_000 });
  await expect(page.getByTestId('video-badge')).toHaveText('Live', { timeout: 15_000 });
  await cdp.send('Network.emulateNetworkConditions', { offline: false, latency: 0, downloadThroughput: -1, uploadThroughput: -1 });
});
