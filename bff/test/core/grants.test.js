// Grants come from the features: a table generated from the feature list and the demo cell file.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { loadCell } from '../../src/core/config/cell.js';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { grantsFor, motionNames, stopNames, mayMoveRobot, argumentChecks, stampedTopics } from '../../src/core/access/grants.js';
import { decode as cborDecode, encode as cborEncode } from 'cbor-x';
import { configFor } from '../../src/core/access/pages.js';
import { matchesAny } from '../../src/core/access/rules.js';
import { namesOf, KINDS, isEmpty } from '../../src/core/features/feature.js';
import { createOpGuard } from '../../src/core/ros/op-guard.js';
import { ControlLease } from '../../src/core/control/lease.js';
import { FEATURES } from '../../src/features/index.js';

const cell = loadCell(path.join(REPO_ROOT, 'config/demo-cell.yaml'), FEATURES);
const OPS = { publish: 'publish', call_service: 'call_service', subscribe: 'subscribe' };
const msgFor = (kind, name, id) => (kind === 'call_service'
  ? { op: 'call_service', id, service: name, args: { name: cell.modules[0].name } }
  : { op: OPS[kind], id, topic: name, ...(kind === 'publish' ? { msg: {} } : {}) });

/** A guard over the demo cell with a role whose grants are derived from `def` (no escape hatch). */
function guardFor(roles) {
  // Every module open to every role here: the per-module roles have their own test below.
  const c = { ...cell, roles, modules: cell.modules.map(({ roles: _, ...m }) => m) };
  const grants = new Map(Object.keys(roles).map((r) => [r, grantsFor(c, FEATURES, r)]));
  const lease = new ControlLease();
  const audit = { entries: [], record(e) { this.entries.push(e); } };
  const guard = createOpGuard({ grantsOf: (r) => grants.get(r), motion: motionNames(c, FEATURES), stamped: stampedTopics(c, FEATURES), lease, audit, checkArgs: argumentChecks(c, FEATURES) });
  const ctx = (role, sid) => ({ session: { username: role, role, sid }, ip: '127.0.0.1', rosapiCalls: new Map(), lastPublishAudit: new Map() });
  const send = (cx, m) => guard.inspect(cx, Buffer.from(JSON.stringify(m)), false);
  return { lease, ctx, send, guard };
}

test('a jog heartbeat is stamped with the moment the BFF lets it through (JSON and CBOR); a client\'s own stamp is replaced', () => {
  assert.deepEqual(stampedTopics(cell, FEATURES), ['/cell/manual/jog']);
  const { lease, ctx, send, guard } = guardFor({ admin: { pages: ['manual'], commands: ['manual'] } });
  const admin = ctx('admin', 'a');
  assert.ok(lease.take(admin.session).ok);
  const jog = { op: 'publish', id: 'j', topic: '/cell/manual/jog', msg: { group: 'arm', mode: 'joint', axis: 0, direction: 1, speed: 0.5, frame: 'base', stamp: { secs: 4e9, nsecs: 0 } } };
  const t0 = Date.now();
  const json = send(admin, jog);
  const cbor = guard.inspect(admin, Buffer.from(cborEncode(jog)), true);
  const t1 = Date.now();
  for (const [v, sent] of [[json, JSON.parse(json.data.toString())], [cbor, cborDecode(cbor.data)]]) {
    assert.equal(v.forward, true);
    const ms = sent.msg.stamp.secs * 1000 + sent.msg.stamp.nsecs / 1e6;
    assert.ok(ms >= t0 && ms <= t1, `stamp ${ms} within ${t0}..${t1}`);
    assert.deepEqual({ ...sent.msg, stamp: undefined }, { ...jog.msg, stamp: undefined }, 'the rest unchanged');
  }
});

const motionRows = FEATURES.flatMap((f) => ['publish', 'call_service'].flatMap((kind) => (namesOf(f, 'motion', cell)[kind] || []).map((name) => ({ f, kind, name }))));

test('the feature list declares motion commands (the table below is not empty)', () => {
  assert.ok(motionRows.length >= 5, JSON.stringify(motionRows.map((r) => r.name)));
  assert.ok(motionRows.some((r) => r.name === '/cell/process/run/goal'), 'the process action goal moves the robot');
});

for (const { f, kind, name } of motionRows) {
  test(`${f.id}: ${kind} ${name} needs the command grant and the control lease`, () => {
    const { lease, ctx, send } = guardFor({
      commander: { pages: [f.id], commands: [f.id] },
      viewer: { pages: [f.id] },
    });
    const viewer = ctx('viewer', 'v');
    const refused = send(viewer, msgFor(kind, name, 'x1'));
    assert.equal(refused.forward, false);
    assert.match(refused.replies[0].data.toString(), /not allowed to/);

    const cmd = ctx('commander', 'c');
    const noLease = send(cmd, msgFor(kind, name, 'x2'));
    assert.equal(noLease.forward, false, 'without the lease');
    assert.match(noLease.replies[0].data.toString(), /needs control: take control first/);

    assert.ok(lease.take(cmd.session).ok);
    assert.equal(send(cmd, msgFor(kind, name, 'x3')).forward, true, 'with the lease');
    const other = ctx('commander', 'c2');
    assert.match(send(other, msgFor(kind, name, 'x4')).replies[0].data.toString(), /which commander holds/);
  });
}

for (const f of FEATURES) {
  for (const kind of ['publish', 'call_service']) {
    for (const name of (namesOf(f, 'commands', cell)[kind] || []).filter((n) => !motionRows.some((r) => r.name === n))) {
      test(`${f.id}: ${kind} ${name} needs the command grant, not the lease`, () => {
        const { ctx, send } = guardFor({ commander: { pages: [f.id], commands: [f.id] }, viewer: { pages: [f.id] } });
        assert.equal(send(ctx('viewer', 'v'), msgFor(kind, name, 'y1')).forward, false);
        assert.equal(send(ctx('commander', 'c'), msgFor(kind, name, 'y2')).forward, true);
      });
    }
  }
}

test('stop is never lease-gated: any role that sees a page that moves the robot may use every stop name', () => {
  const stops = stopNames(cell, FEATURES);
  assert.ok(stops.call_service.includes('/cell/manual/stop'));
  for (const f of FEATURES.filter((x) => mayMoveRobot({ ...cell, roles: { r: { pages: [x.id] } } }, FEATURES, 'r'))) {
    const { lease, ctx, send } = guardFor({ watcher: { pages: [f.id] }, holder: { pages: [f.id], commands: [f.id] } });
    assert.ok(lease.take(ctx('holder', 'h').session).ok, 'someone else holds control');
    for (const kind of ['publish', 'call_service']) {
      for (const name of stops[kind]) assert.equal(send(ctx('watcher', 'w'), msgFor(kind, name, 's')).forward, true, `${f.id}: ${name}`);
    }
  }
  // A page that cannot move the robot gives the robot stop ("Stop robot") and no other stop name.
  const { ctx, send } = guardFor({ reader: { pages: ['sensors'] } });
  assert.equal(send(ctx('reader', 'r'), msgFor('call_service', '/cell/manual/stop', 's')).forward, true, 'the robot stop');
  for (const kind of ['publish', 'call_service']) {
    for (const name of stops[kind].filter((n) => n !== '/cell/manual/stop')) {
      assert.equal(send(ctx('reader', 'r'), msgFor(kind, name, 's')).forward, false, `no ${name}`);
    }
  }
});

test('every role that sees any page may call the robot stop, whatever its pages, and gains nothing else with it', () => {
  const reader = grantsFor({ ...cell, roles: { r: { pages: ['home'] } } }, FEATURES, 'r');
  assert.deepEqual(reader.call_service, ['/cell/get_mode', '/cell/manual/stop']);
  assert.deepEqual(reader.publish, []);
  assert.deepEqual(reader.subscribe, ['/cell/mode'], 'the button reads nothing: it needs only the ROS link');
  const none = grantsFor({ ...cell, roles: { r: { pages: [] } } }, FEATURES, 'r');
  assert.ok(!none.call_service.includes('/cell/manual/stop'), 'a role without a page sees no Stop button and gets no stop');
  // A cell without the manual section has no robot stop to grant.
  const { manual: _m, ...noManual } = cell;
  const bare = { ...noManual, pages: cell.pages.filter((p) => !['manual', 'routines'].includes(p.id)), roles: { r: { pages: ['home'] } } };
  assert.deepEqual(grantsFor(bare, FEATURES, 'r').call_service, ['/cell/get_mode']);
});

// Every role of every shipped cell: "Stop robot" (the robot stop, without the lease) yes; manual moves only with
// the manual commands (and then only with the lease); the lease itself only for a role with a motion command.
const CELLS = ['demo-cell.yaml', 'twin-arm-cell.yaml', 'iiwa-cell.yaml'];
const movers = new Set(FEATURES.filter((f) => !isEmpty(namesOf(f, 'motion', cell))).map((f) => f.id));
for (const file of CELLS) {
  const c = loadCell(path.join(REPO_ROOT, 'config', file), FEATURES);
  for (const [role, def] of Object.entries(c.roles)) {
    const manual = (def.commands || []).includes('manual');
    test(`${file} ${role}: calls /cell/manual/stop without the lease; ${manual ? 'jogs and moves with the lease' : 'never jogs or moves'}`, () => {
      assert.ok(def.pages.length > 0, 'every role of a shipped cell sees a page');
      const grants = new Map(Object.keys(c.roles).map((r) => [r, grantsFor(c, FEATURES, r)]));
      const lease = new ControlLease();
      const guard = createOpGuard({ grantsOf: (r) => grants.get(r), motion: motionNames(c, FEATURES), lease, audit: { record() {} }, checkArgs: argumentChecks(c, FEATURES) });
      const cx = (sid) => ({ session: { username: `${role}-${sid}`, role, sid }, ip: '127.0.0.1', rosapiCalls: new Map(), lastPublishAudit: new Map() });
      const me = cx('me');
      const send = (m) => guard.inspect(me, Buffer.from(JSON.stringify(m)), false);
      const group = c.manual.groups[0].name;
      const jog = { op: 'publish', id: 'j', topic: '/cell/manual/jog', msg: { group, mode: 'joint', axis: 0, direction: 1, speed: 0.1, frame: 'base' } };
      const move = { op: 'call_service', id: 'm', service: '/cell/manual/move_named', args: { group, name: 'home', speed: 0.1, acceleration: 0.1 } };
      const tool = { op: 'call_service', id: 't', service: '/cell/manual/tool', args: {} };
      const stop = { op: 'call_service', id: 's', service: '/cell/manual/stop', args: {} };

      assert.deepEqual(configFor(c, FEATURES, role).stop, { service: '/cell/manual/stop', type: 'std_srvs/Trigger' }, 'the Stop button is shown');
      // Someone else holds control: the stop still goes through, and needs no lease of its own.
      assert.ok(lease.take(cx('other').session).ok);
      assert.equal(send(stop).forward, true, 'stop while another holds control');
      lease.release(cx('other').session);
      assert.equal(send(stop).forward, true, 'stop without the lease');

      for (const m of [jog, move, tool]) {
        const [kind, name] = m.op === 'publish' ? ['publish', m.topic] : ['call_service', m.service];
        if (!manual && matchesAny(def.ros?.[kind], name)) continue; // the escape hatch is the cell file's own business
        const out = send(m);
        assert.equal(out.forward, false, `${name} without the lease`);
        assert.match(String(out.replies[0].data), manual ? /needs control: take control first/ : /not allowed to/);
      }
      if (manual) {
        assert.ok(lease.take(me.session).ok);
        for (const m of [jog, move, tool]) assert.equal(send(m).forward, true, `${m.topic || m.service} with the lease`);
      }
      // Who may hold the lease at all (bff/src/app.js: a command of a feature that moves the robot).
      const mayControl = (def.commands || []).some((x) => movers.has(x));
      if (role === 'maintenance') assert.equal(mayControl, false, 'maintenance never holds control');
      if (!manual) {
        const g = grants.get(role);
        assert.ok(!g.publish.includes('/cell/manual/jog'));
        for (const s of ['/cell/manual/move_named', '/cell/manual/move_relative', '/cell/manual/move_pose', '/cell/manual/tool']) assert.ok(!g.call_service.includes(s), s);
      }
    });
  }
}

test('a role reads what its pages read, and only that (plus the operation mode and the robot stop)', () => {
  for (const f of FEATURES) {
    const g = grantsFor({ ...cell, roles: { r: { pages: [f.id] } } }, FEATURES, 'r');
    const reads = namesOf(f, 'reads', cell);
    for (const k of KINDS) for (const n of reads[k] || []) assert.ok(g[k].includes(n), `${f.id} ${k} ${n}`);
    assert.deepEqual(g.advertise, []);
  }
  const none = grantsFor({ ...cell, roles: { r: { pages: ['home'] } } }, FEATURES, 'r');
  assert.deepEqual(none.subscribe, ['/cell/mode']);
  assert.deepEqual(none.call_service, ['/cell/get_mode', '/cell/manual/stop'], 'plus the robot stop, as every role with a page');
  assert.deepEqual(none.publish, []);
});

test('the demo operator: process and alarm commands, no manual moves, the escape hatch adds /rosout_agg', () => {
  const g = grantsFor(cell, FEATURES, 'operator');
  assert.ok(g.call_service.includes('/cell/alarms/reset'));
  assert.ok(g.call_service.includes('/cell/process/start'));
  assert.ok(!g.call_service.includes('/cell/manual/move_named'));
  assert.ok(!g.publish.includes('/cell/manual/jog'));
  assert.ok(g.subscribe.includes('/rosout_agg'));
  assert.ok(!g.subscribe.includes('/rosout'));
});

test('modules: a role launches and stops only the modules whose roles list it, and only modules of the cell', () => {
  const modules = [
    { name: 'Vision', launch: ['cell_bringup/launch/modules/vision.launch'], nodes: ['/vision'], roles: ['admin'] },
    { name: 'Diagnostics', launch: ['cell_bringup/launch/modules/diagnostics.launch'], nodes: ['/system_monitor'], roles: ['admin', 'operator'] },
    { name: 'Open', launch: ['cell_bringup/launch/modules/diagnostics.launch'], nodes: ['/x'] },
  ];
  const c = { ...cell, modules, roles: { admin: { pages: ['modules'], commands: ['modules'] }, operator: { pages: ['modules'], commands: ['modules'] } } };
  const grants = new Map(Object.keys(c.roles).map((r) => [r, grantsFor(c, FEATURES, r)]));
  const audit = { entries: [], record(e) { this.entries.push(e); } };
  const guard = createOpGuard({ grantsOf: (r) => grants.get(r), motion: motionNames(c, FEATURES), lease: new ControlLease(), audit, checkArgs: argumentChecks(c, FEATURES) });
  const ctx = (role) => ({ session: { username: role, role, sid: role }, ip: '127.0.0.1', rosapiCalls: new Map(), lastPublishAudit: new Map() });
  const call = (role, service, name) => guard.inspect(ctx(role), Buffer.from(JSON.stringify({ op: 'call_service', id: 'x', service, args: { name } })), false);
  for (const service of ['/cell/modules/launch', '/cell/modules/stop']) {
    assert.equal(call('admin', service, 'Vision').forward, true);
    assert.equal(call('operator', service, 'Diagnostics').forward, true);
    assert.equal(call('operator', service, 'Open').forward, true, 'a module without roles: every role that commands modules');
    const refused = call('operator', service, 'Vision');
    assert.equal(refused.forward, false);
    assert.match(JSON.parse(String(refused.replies[0].data)).msg, /operator role may not launch or stop the module "Vision"/);
    assert.equal(call('admin', service, 'Nope').forward, false);
  }
  assert.equal(call('operator', '/cell/modules/output', 'Vision').forward, true, 'reading output is not a command');
  assert.ok(audit.entries.some((e) => e.outcome === 'denied' && /Vision/.test(e.detail)));
});

test('inspect: a role with the page reads the log, the graph and the rates; only echo_roles read a topic\'s last message; a role without the page reads none of it', () => {
  const c = { ...cell, inspect: { echo_roles: ['engineer'] }, roles: { engineer: { pages: ['inspect'] }, viewer: { pages: ['inspect'] }, operator: { pages: ['home'] } } };
  const grants = new Map(Object.keys(c.roles).map((r) => [r, grantsFor(c, FEATURES, r)]));
  const audit = { entries: [], record(e) { this.entries.push(e); } };
  const guard = createOpGuard({ grantsOf: (r) => grants.get(r), motion: motionNames(c, FEATURES), lease: new ControlLease(), audit, checkArgs: argumentChecks(c, FEATURES) });
  const ctx = (role) => ({ session: { username: role, role, sid: role }, ip: '127.0.0.1', rosapiCalls: new Map(), lastPublishAudit: new Map() });
  const call = (role, service) => guard.inspect(ctx(role), Buffer.from(JSON.stringify({ op: 'call_service', id: 'x', service, args: { topic: '/joint_states' } })), false);
  const rows = [
    // service,                      engineer, viewer, operator
    ['/cell/inspect/log', true, true, false],
    ['/cell/inspect/graph', true, true, false],
    ['/cell/inspect/topic_stats', true, true, false],
    ['/cell/inspect/echo', true, false, false],
  ];
  for (const [service, ...allowed] of rows) {
    ['engineer', 'viewer', 'operator'].forEach((role, i) => assert.equal(call(role, service).forward, allowed[i], `${role} ${service}`));
  }
  assert.match(JSON.parse(String(call('viewer', '/cell/inspect/echo').replies[0].data)).msg, /viewer role may not read a topic's messages here/);
  assert.equal(configFor(c, FEATURES, 'engineer').features.inspect.can_echo, true);
  assert.equal(configFor(c, FEATURES, 'viewer').features.inspect.can_echo, false);
  assert.ok(audit.entries.some((e) => e.outcome === 'denied' && e.target === '/cell/inspect/echo'));
  const inspect = FEATURES.find((f) => f.id === 'inspect');
  assert.deepEqual(inspect?.check?.({ echo_roles: ['engineer', 'boss'] }, c), ['inspect.echo_roles[1]: no role "boss" in roles']);
});

/** The demo cell with two motion groups (as config/twin-arm-cell.yaml has): a tool on each. */
function twoGroupCell() {
  const joints = (p) => cell.manual.groups[0].joints.map((j) => `${p}_${j}`);
  return {
    ...cell,
    manual: {
      ...cell.manual,
      groups: [{ name: 'left', joints: joints('left') }, { name: 'right', joints: joints('right') }],
      tools: [{ ...cell.manual.tools[0], name: 'gripper' }, { ...cell.manual.tools[0], name: 'vacuum', group: 'right' }],
    },
    routines: { ...cell.routines, groups: undefined, tools: ['gripper', 'vacuum'] },
    roles: { viewer: { pages: ['manual', 'routines'] }, teacher: { pages: ['routines'] } },
  };
}

test('manual reads /joint_states and, per motion group of the cell file, its state and TCP pose (no cell-wide state topic)', () => {
  const demo = grantsFor({ ...cell, roles: { r: { pages: ['manual'] } } }, FEATURES, 'r');
  for (const t of ['/joint_states', '/cell/manual/arm/state', '/cell/manual/arm/tcp_pose']) assert.ok(demo.subscribe.includes(t), t);
  assert.ok(!demo.subscribe.includes('/cell/manual/state'));
  assert.ok(!demo.subscribe.includes('/cell/manual/tcp_pose'));

  const c = twoGroupCell();
  const g = grantsFor(c, FEATURES, 'viewer');
  for (const t of ['/joint_states', '/cell/manual/left/state', '/cell/manual/left/tcp_pose', '/cell/manual/right/state', '/cell/manual/right/tcp_pose']) {
    assert.ok(g.subscribe.includes(t), t);
  }
  assert.ok(!g.subscribe.some((t) => t === '/cell/manual/state' || t === '/cell/manual/arm/state'));
  // Commands keep their names: one jog topic and one set of services for every group.
  assert.deepEqual(namesOf(FEATURES.find((f) => f.id === 'manual'), 'motion', c).publish, ['/cell/manual/jog']);
  assert.deepEqual(stopNames(c, FEATURES).call_service.filter((s) => s.startsWith('/cell/manual/')), ['/cell/manual/stop']);

  // Through the op guard: a group's state is readable, a made-up group's is not.
  const grants = new Map([['viewer', g]]);
  const guard = createOpGuard({ grantsOf: (r) => grants.get(r), motion: motionNames(c, FEATURES), lease: new ControlLease(), audit: { record() {} }, checkArgs: argumentChecks(c, FEATURES) });
  const cx = { session: { username: 'v', role: 'viewer', sid: 'v' }, ip: '127.0.0.1', rosapiCalls: new Map(), lastPublishAudit: new Map() };
  const sub = (topic) => guard.inspect(cx, Buffer.from(JSON.stringify({ op: 'subscribe', id: 's', topic, type: 'cell_msgs/RobotState' })), false).forward;
  assert.equal(sub('/cell/manual/right/state'), true);
  assert.equal(sub('/cell/manual/middle/state'), false);
  assert.equal(sub('/cell/manual/state'), false);
});

test('routines read the state of the groups they record for, and tell the page each tool\'s group', () => {
  const c = twoGroupCell();
  const g = grantsFor(c, FEATURES, 'teacher');
  assert.ok(g.subscribe.includes('/cell/manual/left/state'));
  assert.ok(g.subscribe.includes('/cell/manual/right/state'));
  assert.ok(!g.subscribe.includes('/cell/manual/left/tcp_pose'), 'the TCP pose topic is the Manual page\'s');
  const routines = FEATURES.find((f) => f.id === 'routines');
  const { action_titles: titles, ...view } = routines.view(c.routines, 'teacher', c);
  assert.deepEqual(view, { groups: ['left', 'right'], tools: ['gripper', 'vacuum'], tool_groups: { gripper: 'left', vacuum: 'right' } });
  assert.deepEqual(Object.keys(titles), ['gripper', 'vacuum'].flatMap((t) => ['open', 'close', 'check_part'].map((a) => `${t}/${a}`)));
  // A routines section that names its groups: only those.
  const only = { ...c, routines: { ...c.routines, groups: ['right'] } };
  const g2 = grantsFor(only, FEATURES, 'teacher');
  assert.ok(g2.subscribe.includes('/cell/manual/right/state'));
  assert.ok(!g2.subscribe.includes('/cell/manual/left/state'));
  assert.deepEqual(routines.view(cell.routines, 'admin', cell).tool_groups, { gripper: 'arm' });
  // The cell file's titles of the tools' actions (per language), for the page to name them as the Manual page does.
  assert.deepEqual(routines.view(cell.routines, 'admin', cell).action_titles['gripper/close'],
    { en: 'Gripper close', es: 'Cerrar pinza', fi: 'Sulje tarttuja', de: 'Greifer schließen' });
  const untitled = structuredClone(cell);
  for (const a of untitled.manual.tools[0].actions) delete a.title;
  assert.deepEqual(routines.view(untitled.routines, 'admin', untitled).action_titles, {});
});
