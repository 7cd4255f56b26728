// A feature's launch file joins the core's exactly when the cell file has the feature's section.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { launchFiles } from '../feature-launch.js';

test('the core launch file first, then one per feature section present', () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'bringup-'));
  fs.mkdirSync(path.join(dir, 'launch/features'), { recursive: true });
  for (const f of ['cell.launch', 'features/modules.launch', 'features/alarms.launch', 'features/README.md']) {
    fs.writeFileSync(path.join(dir, 'launch', f), '<launch/>');
  }
  assert.deepEqual(launchFiles({ cell: {}, alarms: {}, sensors: [] }, dir), [
    path.join(dir, 'launch/cell.launch'), path.join(dir, 'launch/features/alarms.launch'),
  ]);
  assert.deepEqual(launchFiles({ modules: [], alarms: {} }, dir).map((p) => path.basename(p)), ['cell.launch', 'alarms.launch', 'modules.launch']);
  fs.rmSync(path.join(dir, 'launch/features'), { recursive: true });
  assert.deepEqual(launchFiles({ modules: [] }, dir), [path.join(dir, 'launch/cell.launch')]);
});
