import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import yaml from 'js-yaml';
import { loadCell, validateCell, CellConfigError } from '../../src/core/config/cell.js';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { pagesFor, configFor, mayViewPage } from '../../src/core/access/pages.js';
import { tempDir } from '../helpers.js';
import { FEATURES } from '../../src/features/index.js';

const DEMO = path.join(REPO_ROOT, 'config/demo-cell.yaml');
const demo = () => yaml.load(fs.readFileSync(DEMO, 'utf8'));

test('the demo cell file is valid and has a section for every feature', () => {
  const cell = loadCell(DEMO, FEATURES);
  for (const f of FEATURES) if (f.schema) assert.ok(cell[f.id], `section ${f.id}`);
  assert.equal(FEATURES.filter((f) => f.schema).length, 13);
});

const broken = [
  ['unknown top-level field', (d) => { d.colour = 'red'; }, /unknown field "colour"/],
  ['missing cell name', (d) => { delete d.cell.name; }, /cell: missing field "name"/],
  ['role page that does not exist', (d) => { d.roles.operator.pages.push('nowhere'); }, /roles\.operator\.pages\[9\]: unknown page "nowhere"/],
  ['wrong type', (d) => { d.operation_mode.modes = 'idle'; }, /operation_mode\.modes: must be array/],
  ['bad ROS name', (d) => { d.operation_mode.topic = 'cell mode'; }, /operation_mode\.topic: must match pattern/],
  ['initial mode not listed', (d) => { d.operation_mode.initial = 'dancing'; }, /operation_mode\.initial: "dancing"/],
  ['graph kind', (d) => { d.sensors[0].kind = 'pie'; }, /sensors\[0\]\.kind: must be one of time-series, scatter/],
  ['path escape in database dir', (d) => { d.database.directory = '../etc'; }, /database\.directory: must match pattern/],
  ['page without a feature', (d) => { d.pages.push({ id: 'bogus', title: 'Bogus' }); }, /pages\[15\]: no feature "bogus"/],
  ['page without its section', (d) => { delete d.sensors; }, /pages\[5\]: page "sensors" needs the "sensors" section/],
  ['commands of a feature the role does not see', (d) => { d.roles.operator.commands.push('parameters'); }, /roles\.operator\.commands\[4\]: "parameters" is not one of the role's pages/],
  ['commands of a feature that has none', (d) => { d.roles.admin.commands.push('sensors'); }, /roles\.admin\.commands\[7\]: feature "sensors" has no commands/],
  ['module role that does not exist', (d) => { d.modules[0].roles = ['ghost']; }, /modules\[0\]\.roles\[0\]: unknown role "ghost"/],
  ['recorder decimating what is not a topic', (d) => { d.recorder.decimate_s = { 'camera frames': 2 }; }, /recorder\.decimate_s: must match pattern/],
  ['old motion section name', (d) => { d.motion = d.manual; }, /unknown field "motion"/],
  ['an alarm text without its English', (d) => { d.alarms.texts['device.door_open'] = { es: 'Puerta abierta' }; }, /alarms\.texts\.device\.door_open/],
  ['an alarm text in an unknown language', (d) => { d.alarms.texts['device.door_open'] = { en: 'Door open', xx: '?' }; }, /alarms\.texts\.device\.door_open/],
];
for (const [name, mutate, expected] of broken) {
  test(`a cell file with ${name} is refused with the field named`, () => {
    const d = demo();
    mutate(d);
    assert.throws(() => validateCell(d, 'x.yaml', FEATURES), (e) => e instanceof CellConfigError && expected.test(e.message));
  });
}

test('YAML syntax errors and missing files are CellConfigErrors', () => {
  const dir = tempDir();
  fs.writeFileSync(path.join(dir, 'bad.yaml'), 'cell: [unclosed');
  assert.throws(() => loadCell(path.join(dir, 'bad.yaml'), FEATURES), /YAML syntax/);
  assert.throws(() => loadCell(path.join(dir, 'none.yaml'), FEATURES), /cannot read: ENOENT/);
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
  const cell = loadCell(DEMO, FEATURES);
  assert.deepEqual(pagesFor(cell, 'operator').map((p) => p.id), ['home', 'modules', 'process', 'manual', 'scene', 'sensors', 'video', 'alarms', 'recorder']);
  assert.ok(pagesFor(cell, 'admin').some((p) => p.id === 'system'));
  assert.deepEqual(pagesFor(cell, 'nobody'), []);
  assert.equal(mayViewPage(cell, 'operator', 'system'), false);
  assert.equal(mayViewPage(cell, 'admin', 'system'), true);
  const c = configFor(cell, FEATURES, 'operator');
  assert.equal(c.role, 'operator');
  assert.equal(c.operation_mode.topic, '/cell/mode');
  assert.equal(c.roles, undefined, 'the grants of other roles are not sent');
  assert.deepEqual(Object.keys(c.features).sort(), ['alarms', 'manual', 'modules', 'process', 'recorder', 'scene', 'sensors', 'video']);
  assert.deepEqual(c.commands, ['modules', 'process', 'alarms', 'recorder']);
  assert.deepEqual(c.control, { take_over: false, heartbeat_timeout_s: 5 });
  assert.deepEqual(c.stop, { service: '/cell/manual/stop', type: 'std_srvs/Trigger' }, 'every role that sees a page stops the robot');
  const watcher = { ...cell, roles: { ...cell.roles, watcher: { pages: ['sensors'] } } };
  assert.deepEqual(configFor(watcher, FEATURES, 'watcher').stop, c.stop, 'a role that never moves the robot still stops it');
  assert.equal(configFor(cell, FEATURES, 'nobody').stop, null, 'no page, no stop');
  const a = configFor(cell, FEATURES, 'admin');
  assert.equal(a.control.take_over, true);
  assert.equal(a.features.parameters.csv, undefined, 'paths on the robot PC stay there');
  assert.equal(a.features.database.directory, undefined);
});

// One mistake, a line or two: a oneOf/anyOf's other branches and its own "must match exactly one schema" are noise.
const STEP = 'process.operations[0].steps[0]';
const short = [
  ['a typo in a move_named step', { move_named: 'home', speeed: 0.5 }, [`${STEP}: unknown field "speeed"`]],
  ['a tool step without its action', { tool: 'gripper' }, [`${STEP}: missing field "action"`]],
  ['a bad group name', { move_named: 'home', group: 'Bad Name' }, [`${STEP}.group: must match pattern "^[a-z][a-z0-9_-]*$"`]],
  ['two kinds in one step', { move_named: 'home', tool: 'gripper', action: 'open' }, [`${STEP}: only one of "move_named", "tool" is allowed`]],
  ['a step of no kind', { bogus: 1 }, [
    `${STEP}: needs one of the fields "move_named", "move_relative", "move_pose", "tool", "wait_s", "wait_topic", "routine"`,
    `${STEP}: unknown field "bogus"`]],
  ['a text in an offset', { move_relative: [0, 0, 'x', 0, 0, 0] }, [`${STEP}.move_relative[2]: must be number or object`]],
  ['a wait_topic without a condition', { wait_topic: '/x', field: 'data' }, [`${STEP}: needs one of the fields "equals", "above", "below"`]],
  ['a negative wait', { wait_s: -1 }, [`${STEP}.wait_s: must be >= 0`]],
];
for (const [name, step, lines] of short) {
  test(`schema errors are short: ${name}`, () => {
    const d = demo();
    d.process.operations[0].steps[0] = step;
    assert.throws(() => validateCell(d, 'x.yaml', FEATURES), (e) => {
      assert.deepEqual(e.problems, lines);
      return true;
    });
  });
}

test('schema errors are short: a manual tool step and a parameter type rule', () => {
  const d = demo();
  d.manual.tools[0].actions[0].steps[0] = { digital_out: 9, value: true };
  d.parameters.items[0].options = ['a'];
  d.parameters.items[0].default = 'high';
  assert.throws(() => validateCell(d, 'x.yaml', FEATURES), (e) => {
    assert.deepEqual([...e.problems].sort(), [
      'manual.tools[0].actions[0].steps[0].digital_out: must be <= 7',
      'parameters.items[0].default: must be number',
      'parameters.items[0].options: not allowed here',
    ]);
    return true;
  });
});
