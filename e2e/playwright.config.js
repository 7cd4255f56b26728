// Playwright against the whole stack (roscore, rosbridge, ROS nodes, BFF, built PWA) on isolated ports,
// in Debian's Chromium with phone, tablet and desktop profiles.
import fs from 'node:fs';
import { defineConfig, devices } from '@playwright/test';

const chromium = {
  browserName: /** @type {const} */ ('chromium'),
  launchOptions: {
    executablePath: process.env.CHROMIUM_PATH || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--no-first-run'],
  },
};

// Which specs run on which profile, to keep the suite's time: each spec runs on the device of the user it is for
// (the operator's on the phone, the commissioning engineer's on the desktop, the shop floor's tablet between), and
// what depends on the layout or on touch against a mouse on more than one. The profiles run one after the other
// against one stack: a spec leaves the cell as it found it (or as its next run expects).
/** @type {Record<'phone' | 'tablet' | 'desktop', string[]>} */
export const SPECS = {
  phone: ['a11y', 'a11y-alarm', 'shell', 'manual', 'manual-lease', 'alarms', 'audit', 'database', 'modules', 'parameters',
    'plant', 'process', 'recovery', 'routines', 'sensors', 'video', 'video-raw'],
  tablet: ['a11y-glove', 'recorder', 'inspect-graph', 'scene', 'diagnostics'],
  desktop: ['a11y', 'manual', 'inspect', 'access', 'i18n', 'video-raw'],
};
// A spec in no list would never run: refused here rather than found missing later.
const unassigned = fs.readdirSync(new URL('./tests', import.meta.url)).filter((f) => f.endsWith('.spec.js'))
  .map((f) => f.slice(0, -'.spec.js'.length)).filter((n) => !Object.values(SPECS).some((l) => l.includes(n)));
if (unassigned.length) throw new Error(`e2e/playwright.config.js: no profile runs ${unassigned.join(', ')} (add them to SPECS)`);
// E2E_ALL_PROFILES=1: every spec on every profile (174 tests, about 24 minutes on the 2-core machine against 9.5 for
// the lists above; too long for CI's 90-minute budget on a slow day, so not the default yet).
const ALL = process.env.E2E_ALL_PROFILES === '1';
/** @param {'phone' | 'tablet' | 'desktop'} name */
const only = (name) => (ALL ? ['**/*.spec.js'] : SPECS[name].map((n) => `**/${n}.spec.js`));

export default defineConfig({
  testDir: './tests',
  // The tests share one stack whose ROS state (mode, rosbridge process) they change: one at a time.
  workers: 1,
  fullyParallel: false,
  // No retries: a test that fails once is a defect to find, not to hide (the failure-context reporter prints its
  // page snapshot and last steps, as CI keeps only the console).
  retries: 0,
  timeout: 60_000,
  expect: { timeout: 15_000 },
  reporter: [['list'], ['./lib/failure-context-reporter.js']],
  globalSetup: './lib/global-setup.js',
  globalTeardown: './lib/global-teardown.js',
  use: {
    baseURL: `http://localhost:${process.env.E2E_PORT || 18080}`,
    serviceWorkers: 'allow',
    trace: 'off',
    // A hung action or navigation fails with its own call log well before the test's timeout.
    actionTimeout: 15_000,
    navigationTimeout: 30_000,
    screenshot: 'only-on-failure',
  },
  projects: [
    { name: 'phone', testMatch: only('phone'), use: { ...devices['Pixel 7'], ...chromium } },
    { name: 'tablet', testMatch: only('tablet'), use: { ...devices['iPad Mini'], ...chromium } },
    { name: 'desktop', testMatch: only('desktop'), use: { ...devices['Desktop Chrome'], ...chromium } },
  ],
});
