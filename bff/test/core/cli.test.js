import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { UserStore } from '../../src/core/auth/users.js';
import { tempDir } from '../helpers.js';
import yaml from 'js-yaml';

const users = (args, env, input) => spawnSync(process.execPath, ['bff/src/cli/users.js', ...args], {
  cwd: REPO_ROOT, encoding: 'utf8', input, env: { ...process.env, ...env },
});

test('users CLI: add, list, passwd, remove on a fresh DATA_DIR; USERS_FILE honoured', async () => {
  const dir = tempDir();
  const env = { DATA_DIR: dir };
  let r = users(['add', 'eve', '--role', 'operator', '--password-stdin'], env, 'eve-password\n');
  assert.equal(r.status, 0, r.stderr);
  assert.ok(await new UserStore(path.join(dir, 'users.json')).authenticate('eve', 'eve-password'));
  assert.equal(users(['list'], env).stdout, 'eve\toperator\n');
  r = users(['add', 'eve2', '--role', 'wizard', '--password-stdin'], env, 'password123');
  assert.equal(r.status, 2);
  assert.match(r.stderr, /unknown role "wizard".*admin, operator/);
  r = users(['passwd', 'eve', '--password-stdin'], env, 'other-password');
  assert.equal(r.status, 0, r.stderr);
  assert.ok(await new UserStore(path.join(dir, 'users.json')).authenticate('eve', 'other-password'));
  assert.equal(users(['remove', 'eve'], env).status, 0);
  assert.equal(users(['list'], env).stdout, '');
  assert.equal(users(['remove', 'eve'], env).status, 2);

  const file = path.join(tempDir(), 'elsewhere.json');
  assert.equal(users(['add', 'frank', '--role', 'admin', '--password-stdin'], { USERS_FILE: file }, 'frank-password').status, 0);
  assert.ok(fs.existsSync(file));
  assert.equal(users(['bogus'], env).status, 2);
});

// check-config runs the ROS nodes' and the sim's own parsers after the schema (python -m cell_nodes.check, in the
// project's .venv; without one it only warns that those checks were skipped).
const DEMO = path.join(REPO_ROOT, 'config/demo-cell.yaml');
const noVenv = !fs.existsSync(path.join(REPO_ROOT, '.venv/bin/python')) && 'no .venv: the node-level checks are skipped';
const checkConfig = (text) => {
  const file = path.join(tempDir(), 'cell.yaml');
  fs.writeFileSync(file, text);
  return { file, ...spawnSync(process.execPath, ['bff/src/cli/check-config.js', file], { cwd: REPO_ROOT, encoding: 'utf8' }) };
};

test('check-config: a move_named step with an unknown configuration is refused with one line naming the step', { skip: noVenv }, () => {
  const demo = fs.readFileSync(DEMO, 'utf8');
  assert.ok(demo.includes('- { move_named: home }'));
  const r = checkConfig(demo.replace('- { move_named: home }', '- { move_named: hom }')); // the first one only
  assert.equal(r.status, 2, r.stderr);
  assert.equal(r.stdout, '');
  const lines = r.stderr.trim().split('\n');
  assert.equal(lines[0], `${r.file}: invalid cell file (the ROS nodes or the simulator refuse it)`);
  assert.deepEqual(lines.slice(1), [
    "  - process.operations[0].steps[0].move_named: unknown configuration 'hom' for group arm (it has: home, pick_approach)",
  ]);
});

test('check-config: a duplicate module name is refused with one line naming the module', { skip: noVenv }, () => {
  const d = yaml.load(fs.readFileSync(DEMO, 'utf8'));
  d.modules[1].name = d.modules[0].name;
  const r = checkConfig(yaml.dump(d));
  assert.equal(r.status, 2, r.stderr);
  const problems = r.stderr.split('\n').filter((l) => l.startsWith('  - '));
  assert.deepEqual(problems, [`  - modules[1].name: duplicate module name '${d.modules[0].name}'`]);
});

test('check-config: one typo in a process step is one line, not one per step kind', () => {
  const demo = fs.readFileSync(DEMO, 'utf8');
  const r = checkConfig(demo.replace('- { move_named: home }', '- { move_named: home, speeed: 0.5 }'));
  assert.equal(r.status, 2);
  assert.deepEqual(r.stderr.trim().split('\n').slice(1), ['  - process.operations[0].steps[0]: unknown field "speeed"']);
});
