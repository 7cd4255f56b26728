// The second cell (config/twin-arm-cell.yaml: two UR arms, a third role) through the same code: its own stack on
// its own ports and controller addresses, on the tablet (an integrator commissioning a cell). `npm test -w e2e`
// (run.sh) runs it in its second lane, after the demo cell's desktop and tablet run, beside the first lane.
import { defineConfig } from '@playwright/test';
import base from './playwright.config.js';

process.env.E2E_CELL_CONFIG ||= 'config/twin-arm-cell.yaml';
process.env.E2E_PORT ||= '18180';
process.env.E2E_UR_HOSTS ||= 'left=127.0.4.1,right=127.0.4.2';

export default defineConfig({
  ...base,
  testDir: './twin',
  use: { ...base.use, baseURL: `http://localhost:${process.env.E2E_PORT}` },
  // Each behaviour once (playwright.config.js): this cell's specs on the tablet, every one of them.
  projects: base.projects.filter((p) => p.name === 'tablet').map(({ testMatch, ...p }) => p),
});
