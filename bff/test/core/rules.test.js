import { test } from 'node:test';
import assert from 'node:assert/strict';
import { decide, checkMessage, filterRosapiValues, globToRegExp } from '../../src/core/access/rules.js';

const operator = {
  subscribe: ['/cell/*', '/joint_states'],
  publish: [],
  call_service: ['/cell/get_mode', '/cell/process/*', '/rosapi/topics'],
  advertise: [],
  advertise_service: [],
};
const admin = { subscribe: ['*'], publish: ['*'], call_service: ['*'], advertise: ['*'], advertise_service: ['/ui/*'] };

const table = [
  // grants, op, target, allowed
  [operator, 'subscribe', '/cell/mode', true],
  [operator, 'subscribe', '/cell/camera/workbench/image/compressed', true],
  [operator, 'subscribe', '/joint_states', true],
  [operator, 'subscribe', '/joint_states_raw', false],
  [operator, 'subscribe', '/rosout', false],
  [operator, 'subscribe', '/cellar', false],
  [operator, 'publish', '/cell/mode', false],
  [operator, 'advertise', '/cell/mode', false],
  [operator, 'call_service', '/cell/get_mode', true],
  [operator, 'call_service', '/cell/set_mode', false],
  [operator, 'call_service', '/cell/process/start', true],
  [operator, 'call_service', '/rosapi/topics', true],
  [operator, 'call_service', '/rosapi/get_param', false],
  [operator, 'advertise_service', '/ui/prompt', false],
  [operator, 'service_response', '/ui/prompt', false],
  [operator, 'unsubscribe', '/anything', true],
  [operator, 'unadvertise', '/anything', true],
  [operator, 'set_level', undefined, true],
  [operator, 'fragment', undefined, false],
  [operator, 'auth', undefined, false],
  [operator, 'bogus', '/cell/mode', false],
  [operator, 'subscribe', undefined, false],
  [operator, 'subscribe', 'cell/mode', false],
  [admin, 'publish', '/cell/mode', true],
  [admin, 'advertise', '/any/topic', true],
  [admin, 'call_service', '/rosapi/get_param', true],
  [admin, 'advertise_service', '/ui/prompt', true],
  [admin, 'service_response', '/ui/prompt', true],
  [admin, 'advertise_service', '/cell/set_mode', false],
  [admin, 'fragment', undefined, false],
  [undefined, 'subscribe', '/cell/mode', false],
  [{}, 'call_service', '/cell/get_mode', false],
];

for (const [grants, op, target, allowed] of table) {
  const who = grants === operator ? 'operator' : grants === admin ? 'admin' : JSON.stringify(grants);
  test(`${who} ${op} ${target ?? ''} -> ${allowed ? 'allow' : 'deny'}`, () => {
    const d = decide(grants, op, target);
    assert.equal(d.allow, allowed, d.reason);
    assert.ok(d.reason.length > 0);
  });
}

test('globs: * spans segments, ? is one character, regex characters are literal', () => {
  assert.ok(globToRegExp('/cell/*').test('/cell/a/b'));
  assert.ok(globToRegExp('/a?c').test('/abc'));
  assert.ok(!globToRegExp('/a?c').test('/abbc'));
  assert.ok(!globToRegExp('/a.c').test('/abc'));
  assert.ok(globToRegExp('/a.c').test('/a.c'));
});

test('checkMessage reads the target from the op and refuses non-messages', () => {
  assert.equal(checkMessage(operator, { op: 'subscribe', topic: '/cell/mode', id: 's1' }).allow, true);
  const d = checkMessage(operator, { op: 'publish', topic: '/cell/mode', id: 'p1', msg: {} });
  assert.deepEqual([d.allow, d.op, d.id], [false, 'publish', 'p1']);
  for (const bad of [null, 42, 'x', [], {}, { op: 5 }]) assert.equal(checkMessage(admin, bad).allow, false);
});

test('rosapi answers list only what the role may use', () => {
  const topics = filterRosapiValues(operator, '/rosapi/topics', {
    topics: ['/cell/mode', '/secret/cmd', '/joint_states'], types: ['cell_msgs/OperationMode', 'std_msgs/String', 'sensor_msgs/JointState'],
  });
  assert.deepEqual(topics, { topics: ['/cell/mode', '/joint_states'], types: ['cell_msgs/OperationMode', 'sensor_msgs/JointState'] });
  const services = filterRosapiValues(operator, '/rosapi/services', { services: ['/cell/get_mode', '/cell/set_mode', '/rosapi/topics'] });
  assert.deepEqual(services.services, ['/cell/get_mode', '/rosapi/topics']);
  const all = filterRosapiValues(admin, '/rosapi/services', { services: ['/cell/set_mode'] });
  assert.deepEqual(all.services, ['/cell/set_mode']);
  assert.deepEqual(filterRosapiValues(operator, '/rosapi/get_time', { time: { secs: 1, nsecs: 2 } }), { time: { secs: 1, nsecs: 2 } });
});
