// Playwright against the whole stack (roscore, rosbridge, ROS nodes, BFF, built PWA) on isolated ports,
// in Debian's Chromium with phone, tablet and desktop profiles.
import { defineConfig, devices } from '@playwright/test';

const chromium = {
  browserName: /** @type {const} */ ('chromium'),
  launchOptions: {
    executablePath: process.env.CHROMIUM_PATH || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--no-first-run'],
  },
};

export default defineConfig({
  testDir: './tests',
  // Every spec on every profile; `run.sh` runs the profiles in two lanes, each lane with its own stack and directory.
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
    { name: 'phone', use: { ...devices['Pixel 7'], ...chromium } },
    { name: 'tablet', use: { ...devices['iPad Mini'], ...chromium } },
    { name: 'desktop', use: { ...devices['Desktop Chrome'], ...chromium } },
  ],
});
