// The third cell (config/iiwa-cell.yaml: a KUKA LBR iiwa driven through the standard ROS interfaces of its own
// driver, ros_control, simulated) through the same code: its own stack on its own ports, on the phone.
// `npm test -w e2e` (run.sh) runs it in its first lane, after the demo cell's phone run, beside the second lane.
import { defineConfig } from '@playwright/test';
import base from './playwright.config.js';

process.env.E2E_CELL_CONFIG ||= 'config/iiwa-cell.yaml';
process.env.E2E_PORT ||= '18280';

export default defineConfig({
  ...base,
  testDir: './iiwa',
  use: { ...base.use, baseURL: `http://localhost:${process.env.E2E_PORT}` },
  // Each behaviour once (playwright.config.js): this cell's specs on the phone, every one of them.
  projects: base.projects.filter((p) => p.name === 'phone').map(({ testMatch, ...p }) => p),
});
