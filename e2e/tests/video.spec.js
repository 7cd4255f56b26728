// Cameras on a phone: the streams of the cell file, only the shown one subscribed (rostopic info: the rosbridge
// node on that topic, nobody on the other; switching moves it), frames as binary CBOR (no base64 JSON), the
// frame rate and age, "Stale: N s" when frames stop reaching the phone, full screen and pinch-zoom.
import { test, expect } from '@playwright/test';
import { loginAs, openMenu } from '../lib/app.js';
import { rosCli } from '../lib/ros.js';

// (on every profile: the pinch is real touch events through the DevTools protocol, which every profile takes.)

const ROSBRIDGE = '/rosbridge_websocket';
const WORKBENCH = '/cell/camera/workbench/image/compressed';
const GLOBAL = '/cell/camera/global/image/compressed';

/** @param {string} topic */
async function subscribers(topic) {
  const { stdout } = await rosCli(`rostopic info ${topic}`);
  const section = stdout.split(/Subscribers:/)[1] ?? '';
  return [...section.matchAll(/\*\s+(\S+)/g)].map((m) => m[1]);
}

test('only the shown stream is subscribed, in binary CBOR; switching moves the subscription', async ({ page }) => {
  test.slow();
  /** Frames that carried a camera topic: binary (CBOR) or text (JSON with base64). */
  const cameraFrames = { binary: 0, text: 0 };
  page.on('websocket', (ws) => ws.on('framereceived', (f) => {
    if (typeof f.payload === 'string') {
      if (f.payload.includes('/image/compressed')) cameraFrames.text++;
    } else if (f.payload.includes('/image/compressed')) cameraFrames.binary++;
  }));
  await loginAs(page, 'operator');
  await openMenu(page);
  await page.getByTestId('nav-video').click();
  await expect(page).toHaveURL(/\/video$/);

  const workbench = page.getByRole('radio', { name: 'Workbench' });
  await expect(workbench).toBeChecked();
  await expect(page.getByRole('img', { name: 'Workbench camera image' })).toBeVisible({ timeout: 20_000 });
  await expect(page.getByTestId('video-badge')).toHaveText('Live');
  await expect(page.getByTestId('video-detail')).toHaveText(/^\d+\.\d fps · frame \d+(\.\d)? s old$/);
  await expect.poll(() => subscribers(WORKBENCH), { timeout: 15_000 }).toEqual([ROSBRIDGE]);
  expect(await subscribers(GLOBAL)).toEqual([]);
  expect(cameraFrames.binary).toBeGreaterThan(0);
  expect(cameraFrames.text).toBe(0);

  await page.getByRole('radio', { name: 'Global view' }).check();
  await expect(page.getByRole('img', { name: 'Global view camera image' })).toBeVisible({ timeout: 20_000 });
  await expect.poll(() => subscribers(GLOBAL), { timeout: 15_000 }).toEqual([ROSBRIDGE]);
  await expect.poll(() => subscribers(WORKBENCH), { timeout: 15_000 }).toEqual([]);

  // Leaving the page ends the subscription.
  await openMenu(page);
  await page.getByTestId('nav-home').click();
  await expect.poll(() => subscribers(GLOBAL), { timeout: 15_000 }).toEqual([]);
});

test('a stream whose frames stop is marked stale with its age', async ({ page }) => {
  // Between the BFF and this phone, camera frames stop (as on a link that stalls); everything else passes.
  let dropFrames = false;
  await page.routeWebSocket(/\/ros$/, (ws) => {
    const server = ws.connectToServer();
    ws.onMessage((m) => server.send(m));
    server.onMessage((m) => {
      if (dropFrames && typeof m !== 'string' && m.includes('/image/compressed')) return;
      ws.send(m);
    });
  });
  await loginAs(page, 'operator', '/video');
  await expect(page.getByTestId('video-badge')).toHaveText('Live', { timeout: 20_000 });
  dropFrames = true;
  await expect(page.getByTestId('video-status')).toHaveAttribute('data-state', 'stale', { timeout: 10_000 });
  await expect(page.getByTestId('video-badge')).toHaveText(/^Stale: \d+(\.\d)? s$/);
  await expect(page.getByTestId('video-badge')).toHaveText(/^Stale: [3-9] s$/, { timeout: 10_000 });
  await expect(page.getByTestId('video-detail')).toHaveText(/No frame from Workbench for \d+ s/);
  dropFrames = false;
  await expect(page.getByTestId('video-badge')).toHaveText('Live', { timeout: 10_000 });
});

test('full screen, pinch-zoom with two fingers, and Reset zoom', async ({ page, context }) => {
  await loginAs(page, 'operator', '/video');
  await expect(page.getByRole('img', { name: 'Workbench camera image' })).toBeVisible({ timeout: 20_000 });

  await page.getByRole('button', { name: 'Full screen' }).click();
  const exit = page.getByRole('button', { name: 'Exit full screen' });
  await expect(exit).toHaveAttribute('aria-pressed', 'true');
  const frame = await page.getByTestId('video-frame').boundingBox();
  const viewport = page.viewportSize();
  expect(frame && viewport && frame.height > viewport.height * 0.5).toBeTruthy();

  // Two fingers spread apart on the picture (real touch events through the DevTools protocol).
  const box = /** @type {{ x: number, y: number, width: number, height: number }} */ (frame);
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  const cdp = await context.newCDPSession(page);
  const touch = (/** @type {string} */ type, /** @type {number} */ d) => cdp.send('Input.dispatchTouchEvent', {
    type, touchPoints: type === 'touchEnd' ? [] : [{ x: cx - d, y: cy, id: 1 }, { x: cx + d, y: cy, id: 2 }],
  });
  await touch('touchStart', 30);
  for (let d = 40; d <= 120; d += 10) await touch('touchMove', d);
  await touch('touchEnd', 0);
  await expect(page.getByTestId('video-zoom')).toHaveText(/Zoom (3\.\d|4\.0)×/);
  const reset = page.getByRole('button', { name: 'Reset zoom' });
  await expect(reset).toBeEnabled();
  await reset.click();
  await expect(page.getByTestId('video-zoom')).toHaveCount(0);
  await expect(reset).toBeDisabled();

  await page.getByRole('button', { name: 'Zoom in' }).click();
  await expect(page.getByTestId('video-zoom')).toHaveText(/Zoom 1\.5×/);
  await exit.click();
  await expect(page.getByRole('button', { name: 'Full screen' })).toHaveAttribute('aria-pressed', 'false');
});
