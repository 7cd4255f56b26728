// The second cell (config/twin-arm-cell.yaml: two UR arms, a third role) through the same code: its own stack on
// its own ports and controller addresses, on the phone, tablet and desktop profiles one after the other. `npm test -w e2e`
// (run.sh) runs it in its second lane, after the demo cell's desktop run.
import { defineConfig } from '@playwright/test';
import base from './playwright.config.js';

process.env.E2E_CELL_CONFIG ||= 'config/twin-arm-cell.yaml';
process.env.E2E_PORT ||= '18180';
process.env.E2E_UR_HOSTS ||= 'left=127.0.4.1,right=127.0.4.2';

export default defineConfig({
  ...base,
  testDir: './twin',
  use: { ...base.use, baseURL: `http://localhost:${process.env.E2E_PORT}` },
  projects: base.projects,
});
