// Parameters on a phone, through the real page, BFF, rosbridge and the parameters node (its CSV under DATA_DIR):
// a value saved from the page is in the CSV and read back; an invalid value is refused in place and by the node with
// the field named; an edit made while offline stays as a draft; an operator can neither open the page nor write
// through /ros.
import fs from 'node:fs';
import path from 'node:path';
import { test, expect } from '@playwright/test';
import { loginAs, sessionCookie, rosSocket } from '../lib/app.js';

const csvPath = () => path.join(process.env.E2E_DATA_DIR || '', 'parameters.csv');
/** @returns {Record<string, string>} id -> value column of the CSV */
const csvValues = () => Object.fromEntries(fs.readFileSync(csvPath(), 'utf8').trim().split('\n').slice(1)
  .map((l) => l.split(',')).map(([id, value]) => [id, value]));

/** @param {import('@playwright/test').Page} page @param {string} label */
const field = (page, label) => page.getByRole('textbox', { name: label });

test('an admin saves a parameter: the diff first, then the CSV has it and the page reads it back', async ({ page }) => {
  await loginAs(page, 'admin', '/parameters');
  const height = field(page, 'Approach height (mm)');
  await expect(height).toHaveValue(/^\d/);
  const before = await height.inputValue();
  const next = before === '65' ? '70' : '65';
  await height.fill(next);
  const diff = page.getByTestId('parameters-diff');
  await expect(diff).toContainText('Approach height');
  await expect(diff).toContainText(`${before} mm`);
  await expect(diff).toContainText(`${next} mm`);
  await page.getByRole('button', { name: 'Save' }).click();
  await expect(page.getByTestId('parameters-save-feedback')).toContainText('Saved');
  await expect(page.getByTestId('parameters-diff')).toHaveCount(0);
  expect(Number(csvValues().approach_height)).toBe(Number(next));

  await page.reload();
  await expect(field(page, 'Approach height (mm)')).toHaveValue(next);
});

test('an invalid value is refused in place with the field named, and by the node if sent anyway', async ({ page, context, baseURL }) => {
  await loginAs(page, 'admin', '/parameters');
  const parts = field(page, 'Parts per cycle');
  await parts.fill('25');
  await expect(parts).toHaveAttribute('aria-invalid', 'true');
  await expect(page.locator('[data-testid="parameter"][data-id="parts_per_cycle"] [data-testid="parameter-hint"]')).toHaveText(/Parts per cycle: 25 is above the maximum 20/);
  await expect(page.getByRole('button', { name: 'Save' })).toBeDisabled();
  await page.getByRole('button', { name: 'Revert' }).click();
  await expect(parts).toHaveAttribute('aria-invalid', 'false');

  // Past the page: the node refuses, names the field, and writes nothing.
  const csvBefore = fs.readFileSync(csvPath(), 'utf8');
  const ros = await rosSocket(/** @type {string} */ (baseURL), await sessionCookie(context));
  ros.send({ op: 'call_service', id: 'bad', service: '/cell/parameters/set', args: { changes: [{ id: 'parts_per_cycle', value: '25' }, { id: 'approach_height', value: '60' }] } });
  const r = await ros.waitFor((m) => m.op === 'service_response' && m.id === 'bad');
  ros.ws.close();
  expect(r.result).toBe(true);
  expect(r.values.success).toBe(false);
  expect(r.values.errors.map((/** @type {any} */ e) => e.id)).toEqual(['parts_per_cycle']);
  // Said with codes, for the page to say in the user's language (issue 29).
  expect([r.values.code, r.values.errors[0].code]).toEqual(['parameters.nothing_saved_one', 'parameters.above_max']);
  expect(fs.readFileSync(csvPath(), 'utf8')).toBe(csvBefore);
});

test('an edit made offline stays as a draft to review and send when back online', async ({ page, context }) => {
  await loginAs(page, 'admin', '/parameters');
  const recipe = field(page, 'Recipe name');
  await expect(recipe).not.toHaveValue('');
  // A value the CSV does not hold yet (the phone's run saved its own before this profile's).
  const value = `Offline recipe (${test.info().project.name})`;
  await expect(recipe).not.toHaveValue(value);
  await context.setOffline(true);
  await recipe.fill(value);
  await expect(page.getByRole('button', { name: 'Save' })).toBeDisabled();
  await context.setOffline(false);
  await page.reload();
  await expect(page.getByTestId('parameters-draft-note')).toBeVisible();
  await expect(field(page, 'Recipe name')).toHaveValue(value);
  await expect(page.getByTestId('parameters-diff')).toContainText(value);
  await page.getByRole('button', { name: 'Save' }).click();
  await expect(page.getByTestId('parameters-save-feedback')).toContainText('Saved');
  expect(csvValues().recipe_name).toBe(value);
});

test('an operator cannot open the parameters nor write them through /ros', async ({ page, context, baseURL }) => {
  await loginAs(page, 'operator', '/parameters');
  await expect(page.getByTestId('access-denied')).toBeVisible();
  const ros = await rosSocket(/** @type {string} */ (baseURL), await sessionCookie(context));
  ros.send({ op: 'call_service', id: 'w', service: '/cell/parameters/set', args: { changes: [{ id: 'parts_per_cycle', value: '4' }] } });
  ros.send({ op: 'call_service', id: 'r', service: '/cell/parameters/get', args: {} });
  for (const id of ['w', 'r']) {
    const m = await ros.waitFor((x) => x.id === id && (x.op === 'status' || x.op === 'service_response'));
    expect(m.op === 'status' || m.result === false).toBe(true);
  }
  ros.ws.close();
});
