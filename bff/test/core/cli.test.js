import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { UserStore } from '../../src/core/auth/users.js';
import { tempDir } from '../helpers.js';

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
