// The scene feature (the 3D view): its cell-file section (schema and cross-references), what a role's UI and grants
// get from it, and its routes against the real app over HTTP: an arm's URDF from a file or from a ROS parameter (a
// tiny fake master answers the XML-RPC getParam: a real master cannot run in this test file), its mesh filenames
// rewritten, the meshes behind them (relative, file://, absolute, package:// through ROS_PACKAGE_PATH), caching, and
// the 4xx answers for a missing arm, parameter, master, URDF or mesh.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import yaml from 'js-yaml';
import { DOMParser } from '@xmldom/xmldom';
import { FEATURES } from '../../src/features/index.js';
import { validateCell, CellConfigError } from '../../src/core/config/cell.js';
import { configFor } from '../../src/core/access/pages.js';
import { grantsFor } from '../../src/core/access/grants.js';
import scene, { meshType, meshName, findPackage, getParam, SceneError } from '../../src/features/scene/index.js';
import { startBff, login, tempDir } from '../helpers.js';

const FIXTURES = path.join(path.dirname(fileURLToPath(import.meta.url)), '../fixtures/scene');
const UR = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint'];
const IIWA = [1, 2, 3, 4, 5, 6, 7].map((n) => `iiwa_joint_${n}`);
const STL = fs.readFileSync(path.join(FIXTURES, 'meshes/link_1.stl'), 'utf8');

/** A UR group (joint names prefixed unless it is "arm"). @param {string} name */
const urGroup = (name) => ({ name, joints: UR.map((j) => (name === 'arm' ? j : `${name}_${j}`)) });
/** A ros_control group whose driver publishes /<name>/joint_states and /<name>/robot_description. @param {string} name */
const rosControlGroup = (name, rc = {}) => ({
  name, joints: IIWA, driver: 'ros_control',
  ros_control: { joint_states: `/${name}/joint_states`, controller: `/${name}/controller`, robot_description: `/${name}/robot_description`, base_link: 'iiwa_link_0', tip_link: 'iiwa_link_ee', ...rc },
});

/** A minimal cell with a manual and a scene page; the operator does not see the scene. */
function cellWith(scene, groups = [urGroup('arm')]) {
  return {
    cell: { id: 'scene-test', name: 'Scene test cell' },
    pages: [{ id: 'home', title: 'Home' }, { id: 'manual', title: 'Manual motion' }, { id: 'scene', title: '3D view' }],
    roles: { admin: { pages: ['home', 'manual', 'scene'], commands: ['manual'] }, operator: { pages: ['home', 'manual'] } },
    operation_mode: { topic: '/cell/mode', type: 'cell_msgs/OperationMode', modes: ['idle', 'manual'] },
    manual: { groups },
    ...(scene === undefined ? {} : { scene }),
  };
}

/** The problems validateCell reports for a cell ([] when valid). */
function problems(cell) {
  try {
    validateCell(cell, 'c.yaml', FEATURES);
    return [];
  } catch (e) {
    if (!(e instanceof CellConfigError)) throw e;
    return e.problems;
  }
}

// ------------------------------------------------------------------------------------------ schema and check

test('the section is validated; each problem names its field', () => {
  const cases = [
    [{}, 'scene: missing field "arms"'],
    [{ arms: [] }, 'scene.arms: must NOT have fewer than 1 items'],
    [{ arms: [{ group: 'arm', robot_description: '/rd', mesh_dir: 'x' }] }, 'scene.arms[0]: unknown field "mesh_dir"'],
    [{ arms: [{ robot_description: '/rd' }] }, 'scene.arms[0]: missing field "group"'],
    [{ arms: [{ group: 'arm', robot_description: 'robot_description' }] }, 'scene.arms[0].robot_description: must match pattern "^/[A-Za-z0-9_/~]*$"'],
    [{ arms: [{ group: 'arm', robot_description: '/rd', base: [0, 0, 0] }] }, 'scene.arms[0].base: must NOT have fewer than 4 items'],
    [{ arms: [{ group: 'arm', robot_description: '/rd', joint_states: 'js' }] }, 'scene.arms[0].joint_states: must match pattern "^/[A-Za-z0-9_/~]*$"'],
    [{ arms: [{ group: 'arm', urdf: '' }] }, 'scene.arms[0].urdf: must NOT have fewer than 1 characters'],
    [{ markers: 'parts', arms: [{ group: 'arm', robot_description: '/rd' }] }, 'scene.markers: must match pattern "^/[A-Za-z0-9_/~]*$"'],
    [{ stale_after_s: 0, arms: [{ group: 'arm', robot_description: '/rd' }] }, 'scene.stale_after_s: must be > 0'],
    [{ arms: [{ group: 'arm', robot_description: '/rd' }], camera: {} }, 'scene: unknown field "camera"'],
    [{ fixed_frame: '/world', arms: [{ group: 'arm', robot_description: '/rd' }] }, 'scene.fixed_frame: must match pattern "^[A-Za-z_][A-Za-z0-9_/]*$"'],
    [{ fixed_frame: 'world', arms: [{ group: 'arm', robot_description: '/rd', base_frame: 'base link' }] }, 'scene.arms[0].base_frame: must match pattern "^[A-Za-z_][A-Za-z0-9_/]*$"'],
  ];
  for (const [section, expected] of cases) assert.deepEqual(problems(cellWith(section)), [expected], JSON.stringify(section));
});

test('cross-references: manual groups, one URDF source, a group once, an existing urdf file', () => {
  const groups = [urGroup('arm'), rosControlGroup('iiwa')];
  const p = (section) => problems(cellWith(section, groups));
  assert.deepEqual(p({ arms: [{ group: 'arm', robot_description: '/rd' }, { group: 'gantry', robot_description: '/rd' }] }),
    ['scene.arms[1].group: "gantry" is not a motion group of manual.groups (known: arm, iiwa)']);
  assert.deepEqual(problems(cellWith({ arms: [{ group: 'arm', robot_description: '/rd' }] }, [])),
    ['scene.arms[0].group: "arm" is not a motion group of manual.groups (the cell file has none)']);
  assert.deepEqual(p({ arms: [{ group: 'arm', robot_description: '/rd', urdf: '/etc/hostname' }] }),
    ['scene.arms[0]: give robot_description or urdf, not both']);
  assert.deepEqual(p({ arms: [{ group: 'arm' }] }),
    ['scene.arms[0]: needs robot_description (a ROS parameter) or urdf (a file): the group "arm" has driver ur_rtde, and only a ros_control group names its URDF itself']);
  assert.deepEqual(p({ arms: [{ group: 'iiwa' }] }), [], 'a ros_control group brings its own URDF');
  assert.deepEqual(p({ arms: [{ group: 'arm', robot_description: '/rd' }, { group: 'iiwa' }, { group: 'arm', urdf: path.join(FIXTURES, 'two_link.urdf') }] }),
    ['scene.arms[2].group: "arm" is already drawn by scene.arms[0] (one entry per group)']);
  assert.deepEqual(p({ arms: [{ group: 'arm', urdf: '/nonexistent/scene/arm.urdf' }] }), ['scene.arms[0].urdf: no such file: /nonexistent/scene/arm.urdf']);
  assert.deepEqual(p({ arms: [{ group: 'arm', urdf: path.join(FIXTURES, 'two_link.urdf') }] }), []);
  // A base from TF needs the frame TF places it in, and is not also given by hand.
  assert.deepEqual(p({ arms: [{ group: 'iiwa', base_frame: 'iiwa_link_0' }] }), ['scene.arms[0].base_frame: needs scene.fixed_frame (the frame TF places the base in)']);
  assert.deepEqual(p({ fixed_frame: 'world', arms: [{ group: 'iiwa', base_frame: 'iiwa_link_0', base: [0, 0, 0, 0] }] }), ['scene.arms[0]: give base or base_frame, not both']);
  assert.deepEqual(p({ fixed_frame: 'world', arms: [{ group: 'iiwa', base_frame: 'iiwa_link_0' }] }), []);
  // The page needs its section, as every feature with a schema.
  assert.deepEqual(problems(cellWith(undefined)), ['pages[2]: page "scene" needs the "scene" section']);
});

test('a relative urdf that does not exist (relative to the cell file) stops the BFF at start, naming the field', async () => {
  const dir = tempDir('scene-cell-');
  const file = path.join(dir, 'cell.yaml');
  fs.writeFileSync(file, yaml.dump(cellWith({ arms: [{ group: 'arm', urdf: 'urdf/missing.urdf' }] })));
  await assert.rejects(startBff({ CELL_CONFIG: file }), (e) => e instanceof CellConfigError
    && e.problems.length === 1 && e.problems[0] === `scene.arms[0].urdf: no such file: urdf/missing.urdf (relative to the cell file's directory ${dir})`);
});

// ------------------------------------------------------------------------------------------ view and reads

test('view and reads of a UR cell like the demo: /joint_states, the markers, the URDF URL', () => {
  const cell = validateCell(cellWith({ markers: '/sim/parts', arms: [{ group: 'arm', robot_description: '/robot_description' }] }), 'c.yaml', FEATURES);
  assert.deepEqual(scene.view(cell.scene, 'admin', cell), {
    markers: '/sim/parts',
    stale_after_s: 1,
    fixed_frame: null,
    arms: [{ group: 'arm', joints: UR, joint_states: '/joint_states', base: [0, 0, 0, 0], base_frame: null, urdf_url: '/api/scene/arms/arm/urdf' }],
  });
  assert.deepEqual(scene.reads(cell.scene, cell), { subscribe: ['/joint_states', '/sim/parts'] });
  assert.equal(scene.commands, undefined, 'the view commands nothing');
  assert.equal(scene.motion, undefined);
  // Two arms on one topic: subscribed once.
  const twin = validateCell(cellWith({ arms: [{ group: 'left', robot_description: '/left/robot_description', base: [-0.48, 0, 0, 180] }, { group: 'right', robot_description: '/right/robot_description', base: [0.48, 0, 0, 0] }] },
    [urGroup('left'), urGroup('right')]), 'c.yaml', FEATURES);
  assert.deepEqual(scene.reads(twin.scene, twin), { subscribe: ['/joint_states'] });
  assert.deepEqual(scene.view(twin.scene, 'admin', twin).arms.map((a) => [a.group, a.joints[0], a.base]),
    [['left', 'left_shoulder_pan_joint', [-0.48, 0, 0, 180]], ['right', 'right_shoulder_pan_joint', [0.48, 0, 0, 0]]]);
});

test('view and reads of a ros_control cell: the group\'s joint states topic, no markers, a base and staleness given', () => {
  const cell = validateCell(cellWith({ stale_after_s: 2.5, arms: [{ group: 'arm', base: [0.1, -0.2, 0.75, 90] }] }, [rosControlGroup('arm', { joint_states: '/iiwa/joint_states' })]), 'c.yaml', FEATURES);
  assert.deepEqual(scene.view(cell.scene, 'admin', cell), {
    markers: null,
    stale_after_s: 2.5,
    fixed_frame: null,
    arms: [{ group: 'arm', joints: IIWA, joint_states: '/iiwa/joint_states', base: [0.1, -0.2, 0.75, 90], base_frame: null, urdf_url: '/api/scene/arms/arm/urdf' }],
  });
  assert.deepEqual(scene.reads(cell.scene, cell), { subscribe: ['/iiwa/joint_states'] });
  // An explicit joint_states wins over the group's.
  const own = validateCell(cellWith({ arms: [{ group: 'arm', joint_states: '/mirror/joint_states' }] }, [rosControlGroup('arm')]), 'c.yaml', FEATURES);
  assert.equal(scene.view(own.scene, 'admin', own).arms[0].joint_states, '/mirror/joint_states');
  // Grants: a role that sees the page reads them; one that does not, does not.
  const g = grantsFor({ ...cell, roles: { viewer: { pages: ['scene'] }, other: { pages: ['home'] } } }, FEATURES, 'viewer');
  assert.ok(g.subscribe.includes('/iiwa/joint_states'));
  assert.ok(!grantsFor({ ...cell, roles: { other: { pages: ['home'] } } }, FEATURES, 'other').subscribe.includes('/iiwa/joint_states'));
  assert.equal(configFor(cell, FEATURES, 'operator').features.scene, undefined, 'the operator does not see the page');
});

test('with a fixed frame the view reads TF: /tf and /tf_static are granted, each arm says its base frame', () => {
  const cell = validateCell(cellWith({ fixed_frame: 'world', markers: '/sim/parts', arms: [{ group: 'left', robot_description: '/l', base_frame: 'left_base_link' }, { group: 'right', robot_description: '/r', base: [0.48, 0, 0, 0] }] },
    [urGroup('left'), urGroup('right')]), 'c.yaml', FEATURES);
  const view = scene.view(cell.scene, 'admin', cell);
  assert.equal(view.fixed_frame, 'world');
  assert.deepEqual(view.arms.map((a) => [a.group, a.base_frame, a.base]), [['left', 'left_base_link', [0, 0, 0, 0]], ['right', null, [0.48, 0, 0, 0]]]);
  assert.deepEqual(scene.reads(cell.scene, cell), { subscribe: ['/joint_states', '/sim/parts', '/tf', '/tf_static'] });
  const g = grantsFor(cell, FEATURES, 'admin');
  assert.ok(g.subscribe.includes('/tf') && g.subscribe.includes('/tf_static'));
  assert.ok(!grantsFor(cell, FEATURES, 'operator').subscribe.includes('/tf_static'), 'not for a role without the page');
});

test('mesh helpers: content types and base names', () => {
  assert.equal(meshType('a.STL'), 'model/stl');
  assert.equal(meshType('a.dae'), 'model/vnd.collada+xml');
  assert.equal(meshType('a.obj'), 'model/obj');
  assert.equal(meshType('a.ply'), 'application/octet-stream');
  assert.equal(meshName('package://ur_description/meshes/ur5/visual/base.dae'), 'base.dae');
  assert.equal(meshName('file:///opt/my%20robot/link%201.stl'), 'link 1.stl');
  assert.equal(meshName('meshes/link_1.stl'), 'link_1.stl');
});

// ------------------------------------------------------------------------------------------ routes

/** A value as XML-RPC. @param {unknown} v @returns {string} */
function xmlrpcValue(v) {
  const esc = (s) => String(s).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;');
  if (typeof v === 'string') return `<value><string>${esc(v)}</string></value>`;
  if (typeof v === 'boolean') return `<value><boolean>${v ? 1 : 0}</boolean></value>`;
  if (Number.isInteger(v)) return `<value><int>${v}</int></value>`;
  if (typeof v === 'number') return `<value><double>${v}</double></value>`;
  if (Array.isArray(v)) return `<value><array><data>${v.map(xmlrpcValue).join('')}</data></array></value>`;
  return `<value><struct>${Object.entries(v).map(([k, x]) => `<member><name>${esc(k)}</name>${xmlrpcValue(x)}</member>`).join('')}</struct></value>`;
}

/**
 * A stand-in for the ROS master's XML-RPC API: getParam(caller_id, key) -> [1, msg, value] or [-1, msg, 0] when
 * the key is not in `params`. Answers pretty-printed, as rosmaster does. Key "/http500" gets an HTTP 500.
 */
async function fakeMaster(params) {
  const calls = [];
  const server = http.createServer((req, res) => {
    let body = '';
    req.on('data', (c) => (body += c));
    req.on('end', () => {
      const doc = new DOMParser().parseFromString(body, 'text/xml');
      const method = doc.getElementsByTagName('methodName')[0]?.textContent;
      const args = Array.from(doc.getElementsByTagName('string')).map((s) => s.textContent);
      calls.push({ method, args });
      if (args[1] === '/http500') { res.writeHead(500, { 'content-type': 'text/plain' }); res.end('boom'); return; }
      const answer = method !== 'getParam' ? [-1, `unknown method ${method}`, 0]
        : Object.hasOwn(params, args[1]) ? [1, `Parameter [${args[1]}]`, params[args[1]]] : [-1, `Parameter [${args[1]}] is not set`, 0];
      const xml = `<?xml version='1.0'?>\n<methodResponse>\n<params>\n<param>\n${xmlrpcValue(answer)}\n</param>\n</params>\n</methodResponse>\n`;
      res.writeHead(200, { 'content-type': 'text/xml' });
      res.end(xml);
    });
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return { uri: `http://127.0.0.1:${server.address().port}/`, params, calls, close: () => new Promise((r) => { server.closeAllConnections(); server.close(r); }) };
}

/** The URDF a test builds around some mesh filenames (one link each). @param {string[]} meshes */
const urdfWith = (meshes) => `<?xml version="1.0"?>\n<robot name="r"><link name="base_link"><visual><geometry><box size="1 1 1"/></geometry></visual></link>${
  meshes.map((m, i) => `<link name="l${i}"><visual><geometry><mesh filename="${m}"/></geometry></visual></link>`).join('')}</robot>`;

/** The mesh filenames of a URDF text. @param {string} text */
const meshesOf = (text) => Array.from(new DOMParser().parseFromString(text, 'text/xml').getElementsByTagName('mesh')).map((m) => m.getAttribute('filename'));

let t; // the BFF
let master;
let admin; // cookie
let operator;
let dir; // the cell file's directory
let rpp; // ROS_PACKAGE_PATH entries
const savedRpp = process.env.ROS_PACKAGE_PATH;
const SCENE_ARMS = [
  { group: 'arm', urdf: 'urdf/two_link.urdf' },
  { group: 'fileuri', urdf: 'urdf/file_uri.urdf' },
  { group: 'pkg', urdf: 'urdf/package.urdf' },
  { group: 'param', robot_description: '/robot_description', joint_states: '/param/joint_states' },
  { group: 'iiwa' },
  { group: 'unset', robot_description: '/not_set' },
  { group: 'number', robot_description: '/a_number' },
  { group: 'notrobot', robot_description: '/not_robot' },
  { group: 'garbage', robot_description: '/garbage' },
  { group: 'ns', robot_description: '/ns' },
  { group: 'http', robot_description: '/http500' },
  { group: 'secret', robot_description: '/secret' },
  { group: 'gone', urdf: 'urdf/gone.urdf' },
];

before(async () => {
  dir = tempDir('scene-cell-');
  // The cell file's directory: urdf/ with the fixture arm and its mesh, two URDFs the tests write.
  fs.cpSync(FIXTURES, path.join(dir, 'urdf'), { recursive: true });
  const other = tempDir('scene-meshes-');
  fs.writeFileSync(path.join(other, 'tool.obj'), 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n');
  fs.writeFileSync(path.join(dir, 'urdf/file_uri.urdf'), urdfWith([
    pathToFileURL(path.join(dir, 'urdf/meshes/link_1.stl')).href, path.join(other, 'tool.obj'), 'meshes/missing.stl', 'http://example.com/remote.dae',
  ]));
  // ROS_PACKAGE_PATH: a workspace with a package deep under src/, and an entry with a plain directory (no package.xml).
  const ws = tempDir('scene-ws-');
  const pkgDir = path.join(ws, 'src/robots/scene_test_description');
  fs.mkdirSync(path.join(pkgDir, 'meshes'), { recursive: true });
  fs.writeFileSync(path.join(pkgDir, 'package.xml'), '<package format="2"><name>scene_test_description</name></package>');
  fs.writeFileSync(path.join(pkgDir, 'meshes/link_1.dae'), '<?xml version="1.0"?><COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1"/>');
  const plain = tempDir('scene-plain-');
  fs.mkdirSync(path.join(plain, 'plain_meshes/meshes'), { recursive: true });
  fs.writeFileSync(path.join(plain, 'plain_meshes/meshes/part.ply'), 'ply\n');
  rpp = [path.join(ws, 'src'), plain];
  process.env.ROS_PACKAGE_PATH = rpp.join(path.delimiter);
  fs.writeFileSync(path.join(dir, 'urdf/gone.urdf'), urdfWith([]));
  fs.writeFileSync(path.join(dir, 'urdf/package.urdf'), urdfWith([
    'package://scene_test_description/meshes/link_1.dae', 'package://no_such_package/meshes/x.stl', 'package://plain_meshes/meshes/part.ply',
  ]));

  master = await fakeMaster({
    '/robot_description': urdfWith([pathToFileURL(path.join(dir, 'urdf/meshes/link_1.stl')).href, 'urdf/meshes/link_1.stl']),
    '/iiwa/robot_description': fs.readFileSync(path.join(FIXTURES, 'two_link.urdf'), 'utf8').replaceAll('"meshes/link_1.stl"', '"urdf/meshes/link_1.stl"'),
    '/a_number': 42,
    '/not_robot': '<html><body/></html>',
    '/garbage': 'this is <robot not XML',
    '/ns': { robot_description: '<robot/>', joint_limits: { a: 1 } },
  });
  const file = path.join(dir, 'cell.yaml');
  fs.writeFileSync(file, yaml.dump(cellWith({ markers: '/sim/parts', arms: SCENE_ARMS },
    [...SCENE_ARMS.filter((a) => a.group !== 'iiwa').map((a) => urGroup(a.group)), rosControlGroup('iiwa')])));
  t = await startBff({ CELL_CONFIG: file, ROS_MASTER_URI: master.uri });
  admin = (await login(t.base, 'admin', t.passwords.admin)).cookie;
  operator = (await login(t.base, 'operator', t.passwords.operator)).cookie;
});
after(async () => {
  await t?.stop();
  await master?.close();
  if (savedRpp === undefined) delete process.env.ROS_PACKAGE_PATH;
  else process.env.ROS_PACKAGE_PATH = savedRpp;
});

/**
 * GET as admin (or another cookie). A conditional GET goes with Cache-Control: max-age=0 as a browser revalidating
 * its cache sends it (fetch() would add no-cache to a request with If-None-Match, which asks for a full answer).
 */
const get = (p, { cookie = admin, headers = {} } = {}) => fetch(`${t.base}${p}`, {
  headers: { ...(cookie ? { cookie } : {}), ...(headers['if-none-match'] ? { 'cache-control': 'max-age=0' } : {}), ...headers },
});

test('GET /api/config gives the view to a role that sees the page', async () => {
  const c = await (await get('/api/config')).json();
  assert.deepEqual(c.pages.map((p) => p.id), ['home', 'manual', 'scene']);
  assert.equal(c.pages[2].title, '3D view');
  assert.equal(c.features.scene.markers, '/sim/parts');
  assert.deepEqual(c.features.scene.arms.find((a) => a.group === 'param'),
    { group: 'param', joints: urGroup('param').joints, joint_states: '/param/joint_states', base: [0, 0, 0, 0], base_frame: null, urdf_url: '/api/scene/arms/param/urdf' });
  assert.equal(c.features.scene.arms.find((a) => a.group === 'iiwa').joint_states, '/iiwa/joint_states');
  assert.ok(!JSON.stringify(c.features.scene).includes(dir), 'no server path in the view');
  const op = await (await get('/api/config', { cookie: operator })).json();
  assert.equal(op.features.scene, undefined);
});

test('the URDF from a file: mesh filenames rewritten (each distinct one once), XML, no-cache with an ETag, 304 on a revisit', async () => {
  const res = await get('/api/scene/arms/arm/urdf');
  assert.equal(res.status, 200);
  assert.match(res.headers.get('content-type'), /^application\/xml/);
  assert.equal(res.headers.get('cache-control'), 'no-cache');
  const etag = res.headers.get('etag');
  assert.match(etag, /^"[A-Za-z0-9_-]+"$/);
  const text = await res.text();
  assert.deepEqual(meshesOf(text), ['/api/scene/arms/arm/meshes/0/link_1.stl', '/api/scene/arms/arm/meshes/0/link_1.stl']);
  assert.ok(!text.includes(dir) && !text.includes('meshes/link_1.stl"'), 'no server path left');
  const doc = new DOMParser().parseFromString(text, 'text/xml');
  assert.equal(doc.documentElement.nodeName, 'robot');
  assert.equal(doc.getElementsByTagName('box').length, 1, 'the rest of the URDF is untouched');
  assert.equal(doc.getElementsByTagName('joint')[0].getAttribute('name'), 'joint_1');

  const again = await get('/api/scene/arms/arm/urdf', { headers: { 'if-none-match': etag } });
  assert.equal(again.status, 304);
  assert.equal(await again.text(), '');
  const changed = await get('/api/scene/arms/arm/urdf', { headers: { 'if-none-match': '"something-else"' } });
  assert.equal(changed.status, 200);
});

test('the mesh route serves the files the URDF references: relative to the URDF file, cached a day with an ETag', async () => {
  await get('/api/scene/arms/arm/urdf');
  const res = await get('/api/scene/arms/arm/meshes/0/link_1.stl');
  assert.equal(res.status, 200);
  assert.equal(res.headers.get('content-type'), 'model/stl');
  assert.equal(res.headers.get('cache-control'), 'private, max-age=86400');
  const etag = res.headers.get('etag');
  assert.ok(etag);
  assert.equal(await res.text(), STL);
  const again = await get('/api/scene/arms/arm/meshes/0/link_1.stl', { headers: { 'if-none-match': etag } });
  assert.equal(again.status, 304);
  // Only what the URDF references, by its number and name.
  for (const p of ['/api/scene/arms/arm/meshes/1/link_1.stl', '/api/scene/arms/arm/meshes/0/other.stl', '/api/scene/arms/arm/meshes/x/link_1.stl',
    '/api/scene/arms/arm/meshes/-1/link_1.stl', '/api/scene/arms/arm/meshes/00/link_1.stl', '/api/scene/arms/arm/meshes/0/..%2Ftwo_link.urdf']) {
    const r = await get(p);
    assert.equal(r.status, 404, p);
    const body = await r.json();
    assert.match(body.error, /has no mesh/, p);
    assert.equal(body.code, 'scene.no_mesh', p);
  }
  assert.deepEqual(await (await get('/api/scene/arms/arm/meshes/1/link_1.stl')).json(), {
    error: 'the URDF of the arm "arm" has no mesh 1 named link_1.stl', code: 'scene.no_mesh', params: { arm: 'arm', index: '1', name: 'link_1.stl' },
  });
});

test('file:// and absolute mesh paths are served; a missing file, an http:// mesh are a 404 naming the file, not its path', async () => {
  const text = await (await get('/api/scene/arms/fileuri/urdf')).text();
  assert.deepEqual(meshesOf(text), [
    '/api/scene/arms/fileuri/meshes/0/link_1.stl', '/api/scene/arms/fileuri/meshes/1/tool.obj',
    '/api/scene/arms/fileuri/meshes/2/missing.stl', '/api/scene/arms/fileuri/meshes/3/remote.dae',
  ]);
  assert.ok(!text.includes('file://') && !text.includes(dir));
  const stl = await get('/api/scene/arms/fileuri/meshes/0/link_1.stl');
  assert.equal(stl.status, 200);
  assert.equal(await stl.text(), STL);
  const obj = await get('/api/scene/arms/fileuri/meshes/1/tool.obj');
  assert.equal(obj.status, 200);
  assert.equal(obj.headers.get('content-type'), 'model/obj');
  const missing = await get('/api/scene/arms/fileuri/meshes/2/missing.stl');
  assert.equal(missing.status, 404);
  assert.match(missing.headers.get('content-type'), /^application\/json/);
  assert.equal(missing.headers.get('cache-control'), 'no-store');
  const body = await missing.json();
  const error = body.error;
  assert.match(error, /^the mesh missing\.stl cannot be read/);
  assert.ok(!JSON.stringify(body).includes(dir), error);
  assert.equal(body.code, 'scene.mesh_unreadable');
  assert.equal(body.params.name, 'missing.stl');
  const remote = await get('/api/scene/arms/fileuri/meshes/3/remote.dae');
  assert.equal(remote.status, 404);
  assert.deepEqual(await remote.json(), {
    error: 'the mesh remote.dae cannot be read: http:// URIs are not served', code: 'scene.mesh_scheme', params: { name: 'remote.dae', scheme: 'http' },
  });
});

test('package:// meshes are found through ROS_PACKAGE_PATH (a package.xml deep under an entry, or <entry>/<pkg>/)', async () => {
  assert.equal(findPackage('scene_test_description', rpp.join(path.delimiter)), path.join(rpp[0], 'robots/scene_test_description'));
  assert.equal(findPackage('nope', rpp.join(path.delimiter)), null);
  const text = await (await get('/api/scene/arms/pkg/urdf')).text();
  assert.deepEqual(meshesOf(text), ['/api/scene/arms/pkg/meshes/0/link_1.dae', '/api/scene/arms/pkg/meshes/1/x.stl', '/api/scene/arms/pkg/meshes/2/part.ply']);
  const dae = await get('/api/scene/arms/pkg/meshes/0/link_1.dae');
  assert.equal(dae.status, 200);
  assert.equal(dae.headers.get('content-type'), 'model/vnd.collada+xml');
  assert.match(await dae.text(), /<COLLADA/);
  const none = await get('/api/scene/arms/pkg/meshes/1/x.stl');
  assert.equal(none.status, 404);
  assert.deepEqual(await none.json(), {
    error: 'the mesh x.stl cannot be read: the package "no_such_package" is not on ROS_PACKAGE_PATH',
    code: 'scene.mesh_no_package', params: { name: 'x.stl', package: 'no_such_package' },
  });
  // A file of another kind is not served, even when the URDF names it (any node may set the parameter).
  const ply = await get('/api/scene/arms/pkg/meshes/2/part.ply');
  assert.equal(ply.status, 404);
  assert.deepEqual(await ply.json(), { error: 'the mesh part.ply is not served: only .stl, .dae and .obj meshes are', code: 'scene.mesh_format', params: { name: 'part.ply' } });
});

test('the URDF from a ROS parameter through the master\'s getParam; a ros_control group\'s own parameter', async () => {
  const before = master.calls.length;
  const res = await get('/api/scene/arms/param/urdf');
  assert.equal(res.status, 200);
  const text = await res.text();
  assert.deepEqual(master.calls.slice(before), [{ method: 'getParam', args: ['/cell_bff', '/robot_description'] }]);
  assert.deepEqual(meshesOf(text), ['/api/scene/arms/param/meshes/0/link_1.stl', '/api/scene/arms/param/meshes/1/link_1.stl']);
  // file:// (as the simulated iiwa driver sets it), and a relative path (a parameter has no file: the cell file's directory).
  for (const i of [0, 1]) assert.equal(await (await get(`/api/scene/arms/param/meshes/${i}/link_1.stl`)).text(), STL);
  const etag = res.headers.get('etag');
  assert.equal((await get('/api/scene/arms/param/urdf', { headers: { 'if-none-match': etag } })).status, 304);

  const iiwa = await get('/api/scene/arms/iiwa/urdf');
  assert.equal(iiwa.status, 200);
  assert.equal(master.calls.at(-1).args[1], '/iiwa/robot_description');
  assert.deepEqual(meshesOf(await iiwa.text()), ['/api/scene/arms/iiwa/meshes/0/link_1.stl', '/api/scene/arms/iiwa/meshes/0/link_1.stl']);
});

test('a mesh asked before its URDF reads the URDF first; the mapping follows the last URDF read', async () => {
  // A fresh BFF knows no mapping: the mesh request reads the parameter.
  const t2 = await startBff({ CELL_CONFIG: t.env.cellConfig, ROS_MASTER_URI: master.uri });
  try {
    const cookie = (await login(t2.base, 'admin', t2.passwords.admin)).cookie;
    const n = master.calls.length;
    const res = await fetch(`${t2.base}/api/scene/arms/param/meshes/0/link_1.stl`, { headers: { cookie } });
    assert.equal(res.status, 200);
    assert.equal(await res.text(), STL);
    assert.deepEqual(master.calls.slice(n).map((c) => c.args[1]), ['/robot_description']);
    assert.equal((await fetch(`${t2.base}/api/scene/arms/param/meshes/1/link_1.stl`, { headers: { cookie } })).status, 200);
    // The parameter changes (the driver restarted with another arm): the next URDF read gives the new list.
    const old = master.params['/robot_description'];
    master.params['/robot_description'] = urdfWith(['urdf/meshes/link_1.stl']);
    try {
      const text = await (await fetch(`${t2.base}/api/scene/arms/param/urdf`, { headers: { cookie } })).text();
      assert.deepEqual(meshesOf(text), ['/api/scene/arms/param/meshes/0/link_1.stl']);
      assert.equal((await fetch(`${t2.base}/api/scene/arms/param/meshes/1/link_1.stl`, { headers: { cookie } })).status, 404);
      assert.equal((await fetch(`${t2.base}/api/scene/arms/param/meshes/0/link_1.stl`, { headers: { cookie } })).status, 200);
    } finally {
      master.params['/robot_description'] = old;
    }
  } finally {
    await t2.stop();
  }
});

test('parameter errors: not set 404, not a string or not a <robot> document 422, a master that fails 409', async () => {
  const cases = [
    ['unset', 404, 'no URDF on the parameter /not_set (is the arm\'s driver up?)', 'scene.param_unset', { param: '/not_set' }],
    ['number', 422, 'the parameter /a_number does not hold a URDF: it holds a number, not a string', 'scene.param_not_string', { param: '/a_number' }],
    ['ns', 422, 'the parameter /ns does not hold a URDF: it holds a namespace (a dictionary of parameters), not a string', 'scene.param_not_string', { param: '/ns' }],
    ['notrobot', 422, 'the parameter /not_robot does not hold a URDF: its root element is <html>, not <robot>', 'scene.param_root_not_robot', { param: '/not_robot', root: 'html' }],
    ['http', 409, `the ROS master at ${master.uri} does not answer with XML-RPC (HTTP 500): the URDF parameter cannot be read`, 'scene.master_not_xmlrpc', { master: master.uri, detail: 'HTTP 500' }],
  ];
  for (const [group, status, error, code, params] of cases) {
    const res = await get(`/api/scene/arms/${group}/urdf`);
    assert.equal(res.status, status, group);
    assert.deepEqual(await res.json(), { error, code, params }, group);
    // The mesh route reads the URDF when it has no mapping: the same answer.
    const mesh = await get(`/api/scene/arms/${group}/meshes/0/x.stl`);
    assert.equal(mesh.status, status, `${group} mesh`);
  }
  const garbage = await get('/api/scene/arms/garbage/urdf');
  assert.equal(garbage.status, 422);
  const notUrdf = await garbage.json();
  assert.match(notUrdf.error, /^the parameter \/garbage does not hold a URDF: /);
  assert.equal(notUrdf.code, 'scene.param_not_urdf');
  assert.equal(notUrdf.error, `the parameter /garbage does not hold a URDF: ${notUrdf.params.detail}`);
  assert.equal(notUrdf.params.param, '/garbage');
  const unknown = await get('/api/scene/arms/gantry/urdf');
  assert.equal(unknown.status, 404);
  const noArm = await unknown.json();
  assert.match(noArm.error, /^no arm "gantry" in this cell's scene \(arms: arm, fileuri, pkg, param, iiwa,/);
  assert.equal(noArm.code, 'scene.no_arm');
  assert.equal(noArm.params.arm, 'gantry');
  assert.match(noArm.params.arms, /^arm, fileuri, pkg, param, iiwa,/);
  assert.equal((await get('/api/scene/arms/gantry/meshes/0/x.stl')).status, 404);
});

test('a URDF file that is no URDF any more is a 422, one that is gone a 404: the file\'s name, not its path', async () => {
  const file = path.join(dir, 'urdf/gone.urdf');
  assert.equal((await get('/api/scene/arms/gone/urdf')).status, 200);
  fs.writeFileSync(file, '<html/>');
  const bad = await get('/api/scene/arms/gone/urdf');
  assert.equal(bad.status, 422);
  assert.deepEqual(await bad.json(), {
    error: 'the URDF file gone.urdf does not hold a URDF: its root element is <html>, not <robot>', code: 'scene.file_root_not_robot', params: { file: 'gone.urdf', root: 'html' },
  });
  fs.rmSync(file);
  const gone = await get('/api/scene/arms/gone/urdf');
  assert.equal(gone.status, 404);
  assert.deepEqual(await gone.json(), {
    error: 'the URDF file gone.urdf (scene.arms[12].urdf) cannot be read (ENOENT)',
    code: 'scene.file_unreadable', params: { file: 'gone.urdf', field: 'scene.arms[12].urdf', reason: 'ENOENT' },
  });
  fs.writeFileSync(file, urdfWith([])); // back, for the BFFs the next tests start from this cell file
});

test('a ROS master that does not answer: 409 with what cannot be done, and the BFF keeps serving', async () => {
  // startBff's default ROS_MASTER_URI is a port nothing listens on.
  const t2 = await startBff({ CELL_CONFIG: t.env.cellConfig });
  try {
    const cookie = (await login(t2.base, 'admin', t2.passwords.admin)).cookie;
    const res = await fetch(`${t2.base}/api/scene/arms/param/urdf`, { headers: { cookie } });
    assert.equal(res.status, 409);
    assert.deepEqual(await res.json(), {
      error: 'the ROS master at http://127.0.0.1:1 does not answer: the URDF parameter cannot be read', code: 'scene.master_down', params: { master: 'http://127.0.0.1:1' },
    });
    assert.equal((await fetch(`${t2.base}/api/scene/arms/param/meshes/0/link_1.stl`, { headers: { cookie } })).status, 409);
    // A file URDF needs no master.
    assert.equal((await fetch(`${t2.base}/api/scene/arms/arm/urdf`, { headers: { cookie } })).status, 200);
    assert.equal((await fetch(`${t2.base}/api/health`)).status, 200);
  } finally {
    await t2.stop();
  }
});

test('getParam: a master that accepts but never answers, or answers with a fault, is a 409', async () => {
  const hang = http.createServer(() => { /* never answers */ });
  const fault = http.createServer((req, res) => {
    req.resume();
    req.on('end', () => res.end('<?xml version="1.0"?><methodResponse><fault><value><struct>'
      + '<member><name>faultCode</name><value><int>1</int></value></member>'
      + '<member><name>faultString</name><value><string>bad caller</string></value></member></struct></value></fault></methodResponse>'));
  });
  await Promise.all([hang, fault].map((s) => new Promise((r) => s.listen(0, '127.0.0.1', r))));
  try {
    const uri = (s) => `http://127.0.0.1:${s.address().port}`;
    const started = Date.now();
    await assert.rejects(getParam(uri(hang), '/robot_description', { timeoutMs: 200 }),
      (e) => e instanceof SceneError && e.status === 409 && e.message === `the ROS master at ${uri(hang)} does not answer: the URDF parameter cannot be read`
        && e.code === 'scene.master_down');
    assert.ok(Date.now() - started < 2000);
    await assert.rejects(getParam(uri(fault), '/robot_description'),
      (e) => e instanceof SceneError && e.status === 409 && e.message === `the ROS master at ${uri(fault)} refused getParam /robot_description: bad caller`
        && e.code === 'scene.master_refused' && JSON.stringify(e.params) === JSON.stringify({ master: uri(fault), param: '/robot_description', detail: 'bad caller' }));
  } finally {
    for (const s of [hang, fault]) { s.closeAllConnections(); s.close(); }
  }
});

test('a URDF naming one of the BFF\'s own files as a mesh does not get it', async () => {
  const usersFile = t.env.usersFile;
  assert.ok(fs.existsSync(usersFile));
  // A mesh-named link to the users file: the extension passes, the BFF's own files are still refused.
  const disguised = path.join(t.dataDir, 'users.stl');
  fs.symlinkSync(usersFile, disguised);
  master.params['/secret'] = urdfWith([usersFile, pathToFileURL(path.join(t.dataDir, 'audit.log')).href, 'urdf/meshes/link_1.stl', disguised]);
  const text = await (await get('/api/scene/arms/secret/urdf')).text();
  assert.deepEqual(meshesOf(text), ['/api/scene/arms/secret/meshes/0/users.json', '/api/scene/arms/secret/meshes/1/audit.log', '/api/scene/arms/secret/meshes/2/link_1.stl', '/api/scene/arms/secret/meshes/3/users.stl']);
  for (const [i, name] of [[0, 'users.json'], [1, 'audit.log']]) {
    const res = await get(`/api/scene/arms/secret/meshes/${i}/${name}`);
    assert.equal(res.status, 404, name);
    assert.deepEqual(await res.json(), { error: `the mesh ${name} is not served: only .stl, .dae and .obj meshes are`, code: 'scene.mesh_format', params: { name } });
  }
  const res = await get('/api/scene/arms/secret/meshes/3/users.stl');
  assert.equal(res.status, 404);
  assert.deepEqual(await res.json(), { error: 'the mesh users.stl cannot be read: it lies among the BFF\'s own files', code: 'scene.mesh_private', params: { name: 'users.stl' } });
  assert.equal((await get('/api/scene/arms/secret/meshes/2/link_1.stl')).status, 200);
});

test('an operator whose role does not see the page gets 403; no session 401', async () => {
  for (const p of ['/api/scene/arms/arm/urdf', '/api/scene/arms/arm/meshes/0/link_1.stl']) {
    const res = await get(p, { cookie: operator });
    assert.equal(res.status, 403, p);
    assert.deepEqual(await res.json(), { error: 'role "operator" may not use scene', code: 'access.page_denied', params: { role: 'operator', page: 'scene' } });
    assert.equal((await get(p, { cookie: null })).status, 401, p);
  }
});

test('both routes are in the OpenAPI document with every status they answer', async () => {
  const doc = await (await fetch(`${t.base}/api/openapi.json`)).json();
  const urdf = doc.paths['/api/scene/arms/{group}/urdf'].get;
  const mesh = doc.paths['/api/scene/arms/{group}/meshes/{i}/{name}'].get;
  for (const s of ['200', '304', '401', '403', '404', '409', '422']) {
    assert.ok(urdf.responses[s], `urdf ${s}`);
    assert.ok(mesh.responses[s], `mesh ${s}`);
  }
  assert.ok(urdf.responses[200].content['application/xml']);
  assert.deepEqual(Object.keys(mesh.responses[200].content), ['model/stl', 'model/vnd.collada+xml', 'model/obj', 'application/octet-stream']);
});
