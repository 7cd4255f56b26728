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

// Profile coverage by what differs between profiles. The layout, touch and accessibility specs run on the phone, the
// tablet and the desktop. Every other spec is a behaviour (the same code behind any screen). It runs once, on the
// profile of the user it is for: the operator's work on the phone, the engineer's and the admin's tools on the desktop.
export const EVERY_PROFILE = ['layout', 'a11y', 'a11y-alarm', 'a11y-glove', 'shell'];
export const ON_THE_PHONE = ['manual', 'manual-lease', 'process', 'routines', 'alarms', 'recovery', 'video', 'sensors',
  'scene', 'i18n', 'diagnostics'];
export const ON_THE_DESKTOP = ['access', 'audit', 'database', 'inspect', 'inspect-graph', 'modules', 'parameters', 'plant',
  'recorder', 'video-raw'];
const specs = (/** @type {string[]} */ names) => names.map((n) => `**/${n}.spec.js`);
// A spec on none of the lists would run nowhere without a word: refuse to start instead.
const unlisted = fs.readdirSync(new URL('./tests', import.meta.url)).filter((f) => f.endsWith('.spec.js'))
  .map((f) => f.slice(0, -'.spec.js'.length)).filter((n) => ![...EVERY_PROFILE, ...ON_THE_PHONE, ...ON_THE_DESKTOP].includes(n));
if (unlisted.length) throw new Error(`e2e/playwright.config.js: put ${unlisted.join(', ')} on a profile's list`);

export default defineConfig({
  testDir: './tests',
  // `run.sh` runs the profiles in two lanes, each lane with its own stack and directory.
  outputDir: process.env.E2E_OUTPUT_DIR || 'test-results',
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
    { name: 'phone', use: { ...devices['Pixel 7'], ...chromium }, testMatch: specs([...EVERY_PROFILE, ...ON_THE_PHONE]) },
    { name: 'tablet', use: { ...devices['iPad Mini'], ...chromium }, testMatch: specs(EVERY_PROFILE) },
    { name: 'desktop', use: { ...devices['Desktop Chrome'], ...chromium }, testMatch: specs([...EVERY_PROFILE, ...ON_THE_DESKTOP]) },
  ],
});
