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

// The demo cell's main paths (the shell, access rules, manual motion, the process) run on all three profiles.
// The other specs drive /ros directly, change files on the robot PC, check subscriptions with rostopic, kill a
// process of the stack or use two sessions in one browser: once, on the phone (they share one stack and its robot).
const PHONE_ONLY = /(manual-lease|modules|alarms|routines|parameters|sensors|video|database|audit|recovery)\.spec/;

export default defineConfig({
  testDir: './tests',
  // The tests share one stack whose ROS state (mode, rosbridge process) they change: one at a time.
  workers: 1,
  fullyParallel: false,
  // One retry: a test that fails once and passes on its retry is reported as flaky (by name, with its first error
  // and page snapshot) without failing the run; one that fails twice fails it. The stack is real processes on
  // 2 busy cores in CI, and a rare stall there must not cost a 25-minute run, nor go unreported.
  retries: 1,
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
    // The access checks drive /ros directly, and the hold-to-run pad is a thumb control: once, on the phone.
    // The wide layouts' own checks (the camera beside the controls) run on tablet and desktop.
    { name: 'phone', use: { ...devices['Pixel 7'], ...chromium }, testIgnore: /\.wide\.spec/ },
    { name: 'tablet', use: { ...devices['iPad Mini'], ...chromium }, testIgnore: PHONE_ONLY },
    { name: 'desktop', use: { ...devices['Desktop Chrome'], ...chromium }, testIgnore: PHONE_ONLY },
  ],
});
