// An eleventh feature, defined only in a test fixture (its own folder, one list entry), reaches the cell-file
// schema, /api/config, the grants, the lease gate, its routes and the OpenAPI document with no other file changed.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { FEATURES } from '../../src/features/index.js';
import { validateCell } from '../../src/core/config/cell.js';
import widget from '../fixtures/features/widget/index.js';
import { startBff, login, tempDir } from '../helpers.js';

const LIST = [...FEATURES, widget];
let t;
before(async () => {
  const cell = yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8'));
  cell.pages.push({ id: 'widget', title: 'Spinning widget' });
  cell.widget = { speed_topic: '/cell/widget/speed', secret_path: '/etc/widget' };
  cell.roles.operator.pages.push('widget');
  cell.roles.admin.pages.push('widget');
  cell.roles.admin.commands.push('widget');
  const file = path.join(tempDir(), 'cell.yaml');
  fs.writeFileSync(file, yaml.dump(cell));
  t = await startBff({ CELL_CONFIG: file }, { features: LIST });
});
after(() => t.stop());

test('its section is validated with its own schema', () => {
  const cell = yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8'));
  cell.widget = { speed_topic: 'no slash' };
  assert.throws(() => validateCell(cell, 'c.yaml', LIST), /widget\.speed_topic: must match pattern/);
  assert.throws(() => validateCell(cell, 'c.yaml', FEATURES), /unknown field "widget"/, 'without the list entry it is unknown');
});

test('it appears in /api/config for the roles that see it, with its view only', async () => {
  for (const role of ['operator', 'admin']) {
    const { cookie } = await login(t.base, role, t.passwords[role]);
    const c = await (await fetch(`${t.base}/api/config`, { headers: { cookie } })).json();
    assert.ok(c.pages.some((p) => p.id === 'widget' && p.title === 'Spinning widget'), role);
    assert.deepEqual(c.features.widget, { speed_topic: '/cell/widget/speed' });
    assert.equal(c.commands.includes('widget'), role === 'admin');
    assert.ok(c.stop, 'a page that moves the robot brings the stop button');
  }
});

test('its names are in the grants: reads for viewers, commands for commanders, motion behind the lease', () => {
  const op = t.bff.grants.get('operator');
  assert.ok(op.subscribe.includes('/cell/widget/speed'));
  assert.ok(!op.call_service.includes('/cell/widget/configure'));
  assert.ok(op.call_service.includes('/cell/widget/halt'), 'stop without command grant');
  const admin = t.bff.grants.get('admin');
  assert.ok(admin.call_service.includes('/cell/widget/configure'));
  assert.ok(admin.publish.includes('/cell/widget/spin'));
});

test('its routes are served behind the page guard and documented in the OpenAPI document', async () => {
  const doc = await (await fetch(`${t.base}/api/openapi.json`)).json();
  assert.ok(doc.paths['/api/widget/info']);
  const { cookie } = await login(t.base, 'operator', t.passwords.operator);
  const res = await fetch(`${t.base}/api/widget/info`, { headers: { cookie } });
  assert.equal(res.status, 200);
  assert.deepEqual(await res.json(), { topic: '/cell/widget/speed' });
  assert.equal((await fetch(`${t.base}/api/widget/info`)).status, 401);
});
