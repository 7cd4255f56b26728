// The controller address of each motion group (bff/src/core/config/hosts.js): the same rule as the ROS side's
// cell_nodes.manual.config.resolve_hosts.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import { resolveHosts, parseUrHosts, armsOf, isHost, DEFAULT_UR_HOST } from '../../src/core/config/hosts.js';
import { REPO_ROOT } from '../../src/core/config/env.js';

const TWIN = { groups: [{ name: 'left', joints: ['left_elbow_joint'], host: '127.0.2.1' }, { name: 'right', joints: ['right_elbow_joint'], host: '127.0.2.2' }] };
const ONE = { groups: [{ name: 'arm', joints: ['elbow_joint'] }] };

test('without a host anywhere: UR_HOST, else 127.0.0.1', () => {
  assert.equal(DEFAULT_UR_HOST, '127.0.0.1');
  assert.deepEqual(resolveHosts(ONE, {}), { arm: '127.0.0.1' });
  assert.deepEqual(resolveHosts(ONE, { UR_HOST: '' }), { arm: '127.0.0.1' });
  assert.deepEqual(resolveHosts(ONE, { UR_HOST: '10.0.0.5' }), { arm: '10.0.0.5' });
});

test('the cell file\'s host wins over UR_HOST; a group without one takes UR_HOST', () => {
  assert.deepEqual(resolveHosts(TWIN, { UR_HOST: '10.0.0.5' }), { left: '127.0.2.1', right: '127.0.2.2' });
  const mixed = { groups: [{ name: 'a', joints: ['x'], host: 'ur-a.cell.local' }, { name: 'b', joints: ['y'] }] };
  assert.deepEqual(resolveHosts(mixed, { UR_HOST: ' 10.0.0.5 ' }), { a: 'ur-a.cell.local', b: '10.0.0.5' });
});

test('UR_HOSTS overrides per group, the others keep their rule', () => {
  assert.deepEqual(resolveHosts(TWIN, { UR_HOSTS: 'left=127.0.4.1,right=127.0.4.2' }), { left: '127.0.4.1', right: '127.0.4.2' });
  assert.deepEqual(resolveHosts(TWIN, { UR_HOSTS: ' right = 127.0.4.2 , ', UR_HOST: '10.0.0.5' }), { left: '127.0.2.1', right: '127.0.4.2' });
  assert.deepEqual(resolveHosts(ONE, { UR_HOSTS: 'arm=127.0.0.7', UR_HOST: '127.0.0.9' }), { arm: '127.0.0.7' });
  assert.deepEqual(resolveHosts(ONE, { UR_HOSTS: '', UR_HOST: '127.0.0.9' }), { arm: '127.0.0.9' });
});

test('errors name what is wrong: a malformed UR_HOSTS, a group the cell lacks, a bad host (as resolve_hosts in Python)', () => {
  for (const bad of ['left', 'left=', '=127.0.0.1', 'left=127.0.4.1,right']) {
    assert.throws(() => resolveHosts(TWIN, { UR_HOSTS: bad }), /^Error: UR_HOSTS: expected <group>=<host>\[,<group>=<host>\.\.\.\], got '/, bad);
  }
  assert.throws(() => resolveHosts(ONE, { UR_HOSTS: 'left=127.0.4.1' }), /UR_HOSTS: 'left' is not a motion group of this cell \(manual.groups: arm\)/);
  assert.throws(() => resolveHosts(TWIN, { UR_HOSTS: 'left=bad host' }), /UR_HOSTS: left=bad host: expected a host name or an IPv4 address/);
  assert.throws(() => resolveHosts({ groups: [{ name: 'a', host: '' }] }, {}), /manual.groups\[0\].host: expected a host name or an IPv4 address/);
  assert.throws(() => resolveHosts({ groups: [{ name: 'a' }, { name: 'b', host: '300.1.1.1' }] }, {}), /manual.groups\[1\].host/);
  assert.throws(() => resolveHosts(ONE, { UR_HOST: 'no such/host' }), /UR_HOST: expected a host name or an IPv4 address, got 'no such\/host'/);
  // A bad UR_HOST that no group uses is not an error.
  assert.deepEqual(resolveHosts(TWIN, { UR_HOST: 'no such/host' }), { left: '127.0.2.1', right: '127.0.2.2' });
  assert.deepEqual(parseUrHosts(''), []);
  assert.deepEqual(parseUrHosts(undefined), []);
  assert.deepEqual(parseUrHosts('a=h1,,b=h2'), [['a', 'h1'], ['b', 'h2']]);
  for (const h of ['127.0.0.1', 'localhost', 'ur-left.cell.local', 'UR5']) assert.equal(isHost(h), true, h);
  for (const h of ['', ' ', '300.1.1.1', '1.2.3', 'a b', '-x', 'x.123']) assert.equal(isHost(h), false, h);
});

test('no manual section or no groups: no hosts; groups keep the section\'s order', () => {
  assert.deepEqual(resolveHosts(undefined, {}), {});
  assert.deepEqual(resolveHosts(null, {}), {});
  assert.deepEqual(resolveHosts({}, {}), {});
  assert.deepEqual(Object.keys(resolveHosts({ groups: [{ name: 'z' }, { name: 'a' }] }, {})), ['z', 'a']);
});

test('groups with equal hosts are one arm', () => {
  assert.deepEqual(armsOf({ a: 'h1', b: 'h2', c: 'h1' }), [{ host: 'h1', groups: ['a', 'c'] }, { host: 'h2', groups: ['b'] }]);
  assert.deepEqual(armsOf(resolveHosts(TWIN, { UR_HOSTS: 'right=127.0.2.1' })), [{ host: '127.0.2.1', groups: ['left', 'right'] }]);
});

test('the demo cell: its one group at UR_HOST', () => {
  const cell = /** @type {any} */ (yaml.load(fs.readFileSync(path.join(REPO_ROOT, 'config/demo-cell.yaml'), 'utf8')));
  assert.deepEqual(resolveHosts(cell.manual, { UR_HOST: '127.0.0.9' }), { arm: '127.0.0.9' });
});
