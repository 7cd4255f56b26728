// The accessibility audit (axe-core on every page in every theme, glove mode) against the demo cell's stack, on the
// three profiles: `npm run a11y -w e2e`. Not yet part of `npm test`: it goes back once a whole-suite run has passed
// with it (see docs/i18n.md).
import { defineConfig } from '@playwright/test';
import base from './playwright.config.js';

export default defineConfig({ ...base, testDir: './a11y' });
