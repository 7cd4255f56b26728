// Database files on a phone: replace parts.csv from a directory standing for a USB drive on the robot PC, then
// with a file picked on the phone (upload with progress), then restore the backup; the server's refusal of a
// wrong extension is shown as it came. An operator has neither the page nor its API.
//
// The drive: a directory under the stack's first USB root (USB_ROOTS when the stack was started with it, else
// the demo cell's database.usb_roots[0], /media), removed afterwards.
import { test, expect } from '@playwright/test';
import fs from 'node:fs';
import path from 'node:path';
import { loginAs, openMenu } from '../lib/app.js';

// (on every profile; each run puts the files back as it found them.)

const usbRoot = (process.env.USB_ROOTS || '').split(':').filter(Boolean)[0] || '/media';
const drive = path.join(usbRoot, `e2e-usb-${process.pid}`);
const V2 = 'id,name,weight_g\n1,bolt,12\n2,nut,4\n';
const V3 = 'id,name,weight_g\n1,bolt,12\n2,nut,4\n3,washer,1\n4,pin,2\n';

test.beforeAll(() => {
  fs.mkdirSync(path.join(drive, 'exports'), { recursive: true });
  fs.writeFileSync(path.join(drive, 'exports', 'parts_v2.csv'), V2);
  fs.writeFileSync(path.join(drive, 'readme.txt'), 'not a database file');
});
test.afterAll(() => fs.rmSync(drive, { recursive: true, force: true }));

/** @param {import('@playwright/test').Page} page */
const partsMeta = (page) => page.locator('[data-testid="db-file"][data-name="parts.csv"]').getByTestId('db-file-meta');

test('replace from a USB drive, then from a file picked on the phone, then restore the backup', async ({ page }) => {
  test.slow();
  await loginAs(page, 'admin');
  await openMenu(page);
  await page.getByTestId('nav-database').click();
  await expect(page).toHaveURL(/\/database$/);

  // The drive (other drives may be present): its folder, then the file.
  await page.getByRole('combobox', { name: 'USB drive' }).selectOption({ label: `${path.basename(drive)} (${drive})` });
  await page.getByRole('button', { name: 'Open folder exports' }).click();
  await expect(page.getByTestId('drive-path')).toHaveText(`${drive}/exports`);
  await page.getByRole('radio', { name: 'parts_v2.csv' }).check();
  await expect(page.getByRole('combobox', { name: 'Database file to replace' })).toHaveValue('parts.csv');
  await page.getByRole('button', { name: 'Replace parts.csv' }).click();
  const confirm = page.getByRole('dialog', { name: `Replace parts.csv with ${drive}/exports/parts_v2.csv?` });
  await expect(confirm.getByRole('button', { name: 'Yes, replace' })).toBeFocused();
  await confirm.getByRole('button', { name: 'Yes, replace' }).click();
  await expect(confirm).toBeHidden();
  await expect(page.getByTestId('replace-done')).toContainText(`parts.csv replaced with ${drive}/exports/parts_v2.csv.`);
  await expect(partsMeta(page)).toContainText(`${V2.length} B`);

  // From the phone: the file picker, the upload's progress, the result naming the backup of the old file.
  await page.getByRole('radio', { name: 'File on this device' }).check();
  await page.getByLabel('File from this device').setInputFiles({ name: 'parts_v3.csv', mimeType: 'text/csv', buffer: Buffer.from(V3) });
  await page.getByRole('button', { name: 'Replace parts.csv' }).click();
  const upload = page.getByRole('dialog', { name: 'Replace parts.csv with parts_v3.csv from this device?' });
  await expect(upload).toContainText('The current parts.csv is kept as a backup');
  await upload.getByRole('button', { name: 'Yes, replace' }).click();
  const done = page.getByTestId('replace-done');
  await expect(done).toContainText('parts.csv replaced with parts_v3.csv from this device.');
  await expect(done).toContainText(/kept as the backup parts\.csv\.\d{4}-/);
  const backup = /** @type {string} */ ((await done.textContent())?.match(/backup (parts\.csv\.\d{4}-\d\d-\d\dT[\d:.]+Z(?:-\d+)?)/)?.[1]);
  expect(backup).toBeTruthy();
  await expect(partsMeta(page)).toContainText(`${V3.length} B`);

  // Restore that backup (the drive's version): confirmed, then the file is the old one again.
  await page.getByRole('button', { name: 'Show backups of parts.csv' }).click();
  await page.getByRole('button', { name: `Restore parts.csv from ${backup}` }).click();
  const ask = page.getByRole('dialog', { name: `Restore parts.csv from the backup ${backup}?` });
  await ask.getByRole('button', { name: 'Yes, restore' }).click();
  await expect(page.getByTestId('restore-done')).toContainText(`parts.csv restored from ${backup}.`);
  await expect(partsMeta(page)).toContainText(`${V2.length} B`);
  if (process.env.E2E_DATA_DIR) expect(fs.readFileSync(path.join(process.env.E2E_DATA_DIR, 'database', 'parts.csv'), 'utf8')).toBe(V2);
});

test("a wrong extension: the server's refusal is shown as it came", async ({ page }) => {
  await loginAs(page, 'admin', '/database');
  await page.getByRole('combobox', { name: 'USB drive' }).selectOption({ label: `${path.basename(drive)} (${drive})` });
  await page.getByRole('radio', { name: 'readme.txt' }).check();
  await page.getByRole('combobox', { name: 'Database file to replace' }).selectOption('parts.csv');
  await expect(page.getByRole('note')).toContainText('parts.csv takes only .csv files');
  // Escape cancels the confirmation: nothing sent, the focus back on Replace; then confirmed.
  const replace = page.getByRole('button', { name: 'Replace parts.csv' });
  await replace.click();
  const confirm = page.getByRole('dialog', { name: `Replace parts.csv with ${drive}/readme.txt?` });
  await expect(confirm.getByRole('button', { name: 'Yes, replace' })).toBeFocused();
  await page.keyboard.press('Escape');
  await expect(confirm).toBeHidden();
  await expect(replace).toBeFocused();
  await expect(page.getByTestId('replace-failed')).toHaveCount(0);
  await replace.click();
  await confirm.getByRole('button', { name: 'Yes, replace' }).click();
  await expect(page.getByTestId('replace-failed')).toContainText('Could not replace parts.csv: parts.csv needs a .csv file, not .txt');
});

test('an operator has no Database page and no database API', async ({ page }) => {
  await loginAs(page, 'operator');
  await openMenu(page);
  await expect(page.getByTestId('nav-sensors')).toBeVisible();
  await expect(page.getByTestId('nav-video')).toBeVisible();
  await expect(page.getByTestId('nav-database')).toHaveCount(0);
  for (const api of ['/api/database/files', '/api/database/drives', '/api/database/files/parts.csv/backups']) {
    expect((await page.request.get(api)).status(), api).toBe(403);
  }
  expect((await page.request.post('/api/database/files/parts.csv/restore', { data: { backup: 'x' } })).status()).toBe(403);
  await page.goto('/database');
  await expect(page.getByTestId('access-denied')).toBeVisible();
  await expect(page.getByRole('button', { name: /Replace/ })).toHaveCount(0);
});
