import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import yaml from 'js-yaml';
import { loadCell, validateCell, CellConfigError } from '../src/config/cell.js';
import { REPO_ROOT } from '../src/config/env.js';
import { pagesFor, configFor, mayViewPage } from '../src/access/pages.js';
import { tempDir } from './helpers.js';

const DEMO = path.join(REPO_ROOT, 'config/demo-cell.yaml');
const demo = () => yaml.load(fs.readFileSync(DEMO, 'utf8'));

test('the demo cell file is valid and has a section for every feature', () => {
  const cell = loadCell(DEMO);
  for (const s of ['modules', 'sensors', 'video', 'motion', 'process', 'parameters', 'routines', 'safety', 'database']) {
    assert.ok(cell[s], `section ${s}`);
  }
});

const broken = [
  ['unknown top-level field', (d) => { d.colour = 'red'; }, /unknown field "colour"/],
  ['missing cell name', (d) => { delete d.cell.name; }, /cell: missing field "name"/],
  ['role page that does not exist', (d) => { d.roles.operator.pages.push('nowhere'); }, /roles\.operator\.pages\[5\]: unknown page "nowhere"/],
  ['wrong type', (d) => { d.operation_mode.modes = 'idle'; }, /operation_mode\.modes: must be array/],
  ['bad ROS name', (d) => { d.operation_mode.topic = 'cell mode'; }, /operation_mode\.topic: must match pattern/],
  ['initial mode not listed', (d) => { d.operation_mode.initial = 'dancing'; }, /operation_mode\.initial: "dancing"/],
  ['graph kind', (d) => { d.sensors[0].kind = 'pie'; }, /sensors\[0\]\.kind: must be one of time-series, scatter/],
  ['path escape in database dir', (d) => { d.database.directory = '../etc'; }, /database\.directory: must match pattern/],
];
for (const [name, mutate, expected] of broken) {
  test(`a cell file with ${name} is refused with the field named`, () => {
    const d = demo();
    mutate(d);
    assert.throws(() => validateCell(d, 'x.yaml'), (e) => e instanceof CellConfigError && expected.test(e.message));
  });
}

test('YAML syntax errors and missing files are CellConfigErrors', () => {
  const dir = tempDir();
  fs.writeFileSync(path.join(dir, 'bad.yaml'), 'cell: [unclosed');
  assert.throws(() => loadCell(path.join(dir, 'bad.yaml')), /YAML syntax/);
  assert.throws(() => loadCell(path.join(dir, 'none.yaml')), /cannot read: ENOENT/);
});

test('check-config CLI: exit 0 on the demo, exit 2 naming the bad field otherwise', () => {
  const ok = spawnSync(process.execPath, ['bff/src/cli/check-config.js', DEMO], { cwd: REPO_ROOT, encoding: 'utf8' });
  assert.equal(ok.status, 0, ok.stderr);
  const dir = tempDir();
  const d = demo();
  d.roles.admin.ros.publish = [42];
  fs.writeFileSync(path.join(dir, 'c.yaml'), yaml.dump(d));
  const bad = spawnSync(process.execPath, ['bff/src/cli/check-config.js', path.join(dir, 'c.yaml')], { cwd: REPO_ROOT, encoding: 'utf8' });
  assert.equal(bad.status, 2);
  assert.match(bad.stderr, /roles\.admin\.ros\.publish\[0\]: must be string/);
});

test('pages and config are filtered by role', () => {
  const cell = loadCell(DEMO);
  assert.deepEqual(pagesFor(cell, 'operator').map((p) => p.id), ['home', 'process', 'sensors', 'video', 'alarms']);
  assert.ok(pagesFor(cell, 'admin').some((p) => p.id === 'system'));
  assert.deepEqual(pagesFor(cell, 'nobody'), []);
  assert.equal(mayViewPage(cell, 'operator', 'system'), false);
  assert.equal(mayViewPage(cell, 'admin', 'system'), true);
  const c = configFor(cell, 'operator');
  assert.equal(c.role, 'operator');
  assert.equal(c.operation_mode.topic, '/cell/mode');
  assert.equal(c.roles, undefined, 'the grants of other roles are not sent');
});
