// The third cell (config/iiwa-cell.yaml: a KUKA LBR iiwa driven through the standard ROS interfaces of its own
// driver, ros_control, simulated) through the same code: its own stack on its own ports, on the phone, tablet and
// desktop profiles one after the other.
// `npm test -w e2e` runs the demo cell's config, the twin cell's, then this.
import { defineConfig } from '@playwright/test';
import base from './playwright.config.js';

process.env.E2E_CELL_CONFIG ||= 'config/iiwa-cell.yaml';
process.env.E2E_PORT ||= '18280';

export default defineConfig({
  ...base,
  testDir: './iiwa',
  use: { ...base.use, baseURL: `http://localhost:${process.env.E2E_PORT}` },
  projects: (base.projects ?? []).map(({ testMatch, ...p }) => p),
});
