// Manual-motion steps shared by the demo cell's Manual specs (manual.spec.js, manual-lease.spec.js).
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { expect } from '@playwright/test';
import { loginAs } from './app.js';
import { REPO_ROOT } from './stack.js';

export const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
export const arm = cell.manual.groups[0];
export { STILL, expectStandstill, holdJog } from './robot.js';

export const jogMsg = { group: arm.name, mode: 'joint', axis: 0, direction: 1, speed: 0.5, frame: 'base' };

/** @param {import('@playwright/test').Page} page @param {string} [who] */
export async function openManual(page, who = 'admin') {
  await loginAs(page, who, '/manual');
  await expect(page.getByTestId('page-title')).toHaveText(cell.pages.find((/** @type {any} */ p) => p.id === 'manual').title);
}
