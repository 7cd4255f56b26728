// `npm run service -- install|uninstall|status`: the unit and env file texts (pure functions), and the CLI writing
// into a temporary --root (systemctl is never called with --root). Run: node --test scripts/test/service.test.js
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import {
  DEFAULT_ENV_FILE, ENV_VARS, effectiveSettings, envFile, envValue, execWord, parseKeyValues, serviceName, unitFile,
} from '../service/unit.js';

const REPO = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const CLI = path.join(REPO, 'scripts/service.js');
const NODE = process.execPath;

/** The environment of a CLI run: none of the settings, sudo or --root variables of the caller's. */
function cleanEnv(extra = {}) {
  const env = { ...process.env };
  for (const v of ENV_VARS) delete env[v.name];
  for (const k of ['SUDO_USER', 'SUDO_UID', 'SUDO_GID', 'SUDO_COMMAND', 'SERVICE_ROOT', 'SERVICE_TEST_UID']) delete env[k];
  return { ...env, ...extra };
}

/** @param {string[]} args @param {Record<string, string>} [env] */
function cli(args, env = {}) {
  const r = spawnSync(NODE, [CLI, ...args], { cwd: REPO, env: cleanEnv(env), encoding: 'utf8', timeout: 20000 });
  return { code: r.status, out: r.stdout, err: r.stderr };
}

const tmpDirs = [];
const tmpRoot = () => { const d = fs.mkdtempSync(path.join(os.tmpdir(), 'service-test-')); tmpDirs.push(d); return d; };
after(() => { for (const d of tmpDirs) fs.rmSync(d, { recursive: true, force: true }); });
const mode = (f) => fs.statSync(f).mode & 0o777;
/** Every file under a directory, relative. */
const filesUnder = (dir) => fs.readdirSync(dir, { recursive: true }).map(String)
  .filter((f) => fs.statSync(path.join(dir, f)).isFile()).sort();

/** An executable on PATH, or null. */
function which(cmd) {
  for (const d of (process.env.PATH || '').split(':').filter(Boolean)) {
    try { fs.accessSync(path.join(d, cmd), fs.constants.X_OK); return path.join(d, cmd); } catch { /* next */ }
  }
  return null;
}

const DIRECTIVES = {
  Unit: ['Description', 'Documentation', 'After', 'Wants'],
  Service: ['Type', 'User', 'WorkingDirectory', 'EnvironmentFile', 'ExecStart', 'Restart', 'RestartSec',
    'RestartPreventExitStatus', 'KillSignal', 'KillMode', 'TimeoutStopSec', 'StandardOutput', 'StandardError',
    'SyslogIdentifier', 'LimitNICE', 'CPUWeight', 'IOWeight'],
  Install: ['WantedBy'],
};

/**
 * Problems of a unit file: its structure (sections, known keys, each once) always; and, where systemd-analyze
 * exists, what `systemd-analyze verify` says about it (it exits 0 on settings it ignores, so its messages count).
 * @returns {{problems: string[], verified: boolean}}
 */
function checkUnit(file) {
  const problems = [];
  let section = '';
  const seen = new Set();
  for (const [i, line] of fs.readFileSync(file, 'utf8').split('\n').entries()) {
    if (!line.trim() || line.startsWith('#')) continue;
    const m = /^\[(\w+)\]$/.exec(line);
    if (m) { section = m[1]; if (!DIRECTIVES[section]) problems.push(`line ${i + 1}: unknown section ${line}`); continue; }
    const kv = /^([A-Za-z]+)=(.*)$/.exec(line);
    if (!kv) { problems.push(`line ${i + 1}: not Key=value: ${line}`); continue; }
    if (!DIRECTIVES[section]?.includes(kv[1])) problems.push(`line ${i + 1}: ${kv[1]} unexpected in [${section}]`);
    if (seen.has(`${section}.${kv[1]}`)) problems.push(`line ${i + 1}: ${kv[1]} twice`);
    seen.add(`${section}.${kv[1]}`);
  }
  const analyze = which('systemd-analyze');
  if (!analyze) return { problems, verified: false };
  const r = spawnSync(analyze, ['verify', file], { encoding: 'utf8', timeout: 30000 });
  if (r.status !== 0) problems.push(`systemd-analyze verify exited ${r.status}: ${r.stderr}`);
  const base = path.basename(file);
  for (const l of `${r.stdout}\n${r.stderr}`.split('\n')) if (l.includes(base)) problems.push(`systemd-analyze: ${l}`);
  return { problems, verified: true };
}

const OPTS = { repoRoot: REPO, nodePath: NODE, user: 'alice', envFile: DEFAULT_ENV_FILE };

test('the unit has every directive, absolute paths, and the env file', () => {
  const u = unitFile(OPTS);
  const kv = parseKeyValues(u);
  assert.match(u, /^\[Unit\]$[\s\S]*^\[Service\]$[\s\S]*^\[Install\]$/m);
  assert.ok(kv.Description.length > 10);
  assert.equal(kv.After, 'network-online.target');
  assert.equal(kv.Wants, 'network-online.target');
  assert.equal(kv.Type, 'simple');
  assert.equal(kv.User, 'alice');
  assert.equal(kv.WorkingDirectory, REPO);
  assert.ok(path.isAbsolute(kv.WorkingDirectory));
  assert.equal(kv.EnvironmentFile, '/etc/robot-cell/robot-cell.env');
  // node itself, by absolute path, on the supervisor: no npm, no bootstrap at boot
  assert.equal(kv.ExecStart, `${NODE} ${path.join(REPO, 'scripts/stack.js')}`);
  assert.ok(path.isAbsolute(NODE));
  assert.doesNotMatch(u, /npm start|bootstrap\.sh/);
  assert.equal(kv.Restart, 'on-failure');
  assert.equal(kv.RestartSec, '5');
  assert.equal(kv.RestartPreventExitStatus, '2');
  assert.equal(kv.KillSignal, 'SIGINT');
  assert.equal(kv.KillMode, 'mixed');
  assert.equal(kv.TimeoutStopSec, '15');
  assert.equal(kv.StandardOutput, 'journal');
  assert.equal(kv.StandardError, 'journal');
  assert.equal(kv.SyslogIdentifier, 'robot-cell');
  assert.equal(kv.LimitNICE, '-10'); // cell_nodes/priority.py raises the motion path to exactly this
  assert.equal(kv.CPUWeight, '1000');
  assert.equal(kv.IOWeight, '1000');
  assert.equal(kv.WantedBy, 'multi-user.target');
  assert.match(u, /^\[Install\]\nWantedBy=multi-user.target\n$/m);
  assert.equal(parseKeyValues(unitFile({ ...OPTS, name: 'cell-b', envFile: '/etc/cell-b.env' })).SyslogIdentifier, 'cell-b');
  assert.equal(parseKeyValues(unitFile({ ...OPTS, envFile: '/opt/x y/cell.env' })).EnvironmentFile, '/opt/x y/cell.env');
});

test('the unit refuses relative paths and bad names, and escapes what systemd would expand', () => {
  assert.throws(() => unitFile({ ...OPTS, repoRoot: 'relative/repo' }), /absolute/);
  assert.throws(() => unitFile({ ...OPTS, nodePath: 'node' }), /absolute/);
  assert.throws(() => unitFile({ ...OPTS, envFile: 'cell.env' }), /absolute/);
  assert.throws(() => unitFile({ ...OPTS, user: 'bad user' }), /user/);
  assert.throws(() => unitFile({ ...OPTS, repoRoot: '/a\nExecStartPre=/opt/x/evil' }), /one-line/);
  assert.equal(execWord('/opt/node-v20/node'), '/opt/node-v20/node');
  assert.equal(execWord('/opt/my cell/scripts/stack.js'), '"/opt/my cell/scripts/stack.js"');
  assert.equal(execWord('/opt/100%/$HOME'), '/opt/100%%/$$HOME');
  assert.equal(execWord('/opt/a"b'), '"/opt/a\\"b"');
  const u = unitFile({ ...OPTS, repoRoot: '/srv/cell 50%' });
  assert.match(u, /^WorkingDirectory=\/srv\/cell 50%%$/m);
  assert.match(u, /^ExecStart=\S+ "\/srv\/cell 50%%\/scripts\/stack.js"$/m);
  assert.equal(serviceName('robot-cell.service'), 'robot-cell');
  assert.throws(() => serviceName('a/b'), /service name/);
  assert.throws(() => serviceName('cell@1'), /service name/);
});

test('the env file: the settings in effect, commented defaults, values systemd reads back', () => {
  const settings = effectiveSettings({ PORT: '18080', DATA_DIR: '/var/lib/cell', UR_SIM: '0', SIM_ARGS: '--no-cameras --speed 4' });
  const text = envFile({ settings, repoRoot: REPO });
  const kv = parseKeyValues(text);
  assert.equal(kv.PORT, '18080');
  assert.equal(kv.TLS_PORT, '8443');
  assert.equal(kv.ROS_MASTER_URI, 'http://127.0.0.1:11311');
  assert.equal(kv.ROSBRIDGE_PORT, '9090');
  assert.equal(kv.CELL_CONFIG, path.join(REPO, 'config/demo-cell.yaml'));
  assert.equal(kv.DATA_DIR, '/var/lib/cell');
  assert.equal(kv.UR_HOST, '127.0.0.1');
  assert.equal(kv.UR_SIM, '0');
  assert.equal(kv.SIM_ARGS, '--no-cameras --speed 4');
  // USERS_FILE follows DATA_DIR unless set; the unset optional ones are commented defaults
  assert.equal(kv.USERS_FILE, undefined);
  assert.match(text, /^#USERS_FILE=$/m);
  assert.match(text, /^#SESSION_TTL_S=1800$/m);
  assert.match(text, /^#TLS_CERT=$/m);
  for (const v of ENV_VARS) assert.match(text, new RegExp(`^#? ?.*\\n#?${v.name}=`, 'm'), v.name);
  assert.match(text, /# BFF HTTP port \(default: 8080\)\nPORT=18080/);
  // defaults of the contract when nothing is set, absolute paths
  const d = parseKeyValues(envFile({ settings: effectiveSettings({}), repoRoot: REPO }));
  assert.equal(d.PORT, '8080');
  assert.equal(d.DATA_DIR, path.join(REPO, '.data'));
  assert.equal(parseKeyValues(envFile({ settings: effectiveSettings({ USERS_FILE: '/etc/cell/users.json' }), repoRoot: REPO })).USERS_FILE,
    '/etc/cell/users.json');
  assert.equal(envValue('a b"$c'), '"a b\\"\\$c"');
  assert.throws(() => envValue('a\nb'), /one-line/);
});

test('install into a --root: the unit, the env file (0640), no systemctl, the commands to run', () => {
  const root = tmpRoot();
  const r = cli(['install', '--root', root, '--no-bootstrap', '--user', 'alice'], { PORT: '18080', UR_SIM: '0' });
  assert.equal(r.code, 0, r.err);
  const unitPath = path.join(root, 'etc/systemd/system/robot-cell.service');
  const envPath = path.join(root, 'etc/robot-cell/robot-cell.env');
  assert.deepEqual(filesUnder(root), ['etc/robot-cell/robot-cell.env', 'etc/systemd/system/robot-cell.service']);
  assert.equal(fs.readFileSync(unitPath, 'utf8'), unitFile(OPTS));
  assert.equal(mode(unitPath), 0o644);
  assert.equal(mode(envPath), 0o640);
  const env = parseKeyValues(fs.readFileSync(envPath, 'utf8'));
  assert.equal(env.PORT, '18080');
  assert.equal(env.UR_SIM, '0');
  assert.equal(env.DATA_DIR, path.join(REPO, '.data'));
  assert.match(r.out, /systemctl was not called/);
  assert.match(r.out, /sudo systemctl daemon-reload\n\s+sudo systemctl enable --now robot-cell/);
});

test('a second install rewrites the unit but never the env file', () => {
  const root = tmpRoot();
  assert.equal(cli(['install', '--root', root, '--no-bootstrap', '--user', 'alice']).code, 0);
  const envPath = path.join(root, 'etc/robot-cell/robot-cell.env');
  const edited = `${fs.readFileSync(envPath, 'utf8')}UR_HOST=192.168.1.10\n`;
  fs.writeFileSync(envPath, edited);
  const r = cli(['install', '--root', root, '--no-bootstrap', '--user', 'bob'], { PORT: '19090' });
  assert.equal(r.code, 0, r.err);
  assert.match(r.out, /kept .*robot-cell\.env/);
  assert.equal(fs.readFileSync(envPath, 'utf8'), edited);
  assert.equal(parseKeyValues(fs.readFileSync(path.join(root, 'etc/systemd/system/robot-cell.service'), 'utf8')).User, 'bob');
});

test('the user: SUDO_USER under sudo, else the current one; --name and --environment-file; SERVICE_ROOT', () => {
  const root = tmpRoot();
  const r = cli(['install', '--root', root, '--no-bootstrap'], { SUDO_USER: 'carol', SERVICE_TEST_UID: '0' });
  assert.equal(r.code, 0, r.err);
  assert.equal(parseKeyValues(fs.readFileSync(path.join(root, 'etc/systemd/system/robot-cell.service'), 'utf8')).User, 'carol');
  const me = os.userInfo().username;
  const root2 = tmpRoot();
  assert.equal(cli(['install', '--no-bootstrap', '--name', 'cell-b.service', '--environment-file', '/opt/cell-b/cell.env'],
    { SERVICE_ROOT: root2, SUDO_USER: 'carol', SERVICE_TEST_UID: '1000' }).code, 0);
  assert.deepEqual(filesUnder(root2), ['etc/systemd/system/cell-b.service', 'opt/cell-b/cell.env']);
  const kv = parseKeyValues(fs.readFileSync(path.join(root2, 'etc/systemd/system/cell-b.service'), 'utf8'));
  assert.equal(kv.User, me); // SUDO_USER counts only when running as root
  assert.equal(kv.EnvironmentFile, '/opt/cell-b/cell.env'); // the unit names the real path, not the --root one
  assert.equal(kv.SyslogIdentifier, 'cell-b');
  const s = cli(['status', '--name', 'cell-b'], { SERVICE_ROOT: root2 });
  assert.equal(s.code, 0, s.err);
  assert.match(s.out, new RegExp(`env file: ${root2}/opt/cell-b/cell.env: exists \\(mode 0640\\)`));
});

test('status and uninstall: the unit goes, the env file and DATA_DIR stay', () => {
  const root = tmpRoot();
  let s = cli(['status', '--root', root]);
  assert.equal(s.code, 1);
  assert.match(s.out, /not installed/);
  assert.equal(cli(['install', '--root', root, '--no-bootstrap', '--user', 'alice'], { DATA_DIR: '/var/lib/cell' }).code, 0);
  s = cli(['status', '--root', root]);
  assert.equal(s.code, 0, s.err);
  assert.match(s.out, /robot-cell\.service: installed/);
  assert.ok(s.out.includes(`ExecStart=${NODE} ${REPO}/scripts/stack.js`));
  assert.match(s.out, /EnvironmentFile=\/etc\/robot-cell\/robot-cell\.env/);
  assert.match(s.out, /robot-cell\.env: exists \(mode 0640\)/);
  assert.match(s.out, /DATA_DIR=\/var\/lib\/cell/);
  assert.match(s.out, /journalctl -u robot-cell -n 20 --no-pager/);
  const u = cli(['uninstall', '--root', root]);
  assert.equal(u.code, 0, u.err);
  assert.deepEqual(filesUnder(root), ['etc/robot-cell/robot-cell.env']);
  assert.match(u.out, /kept: the env file .*robot-cell\.env and DATA_DIR \/var\/lib\/cell/);
  s = cli(['status', '--root', root]);
  assert.equal(s.code, 1);
  assert.match(s.out, /not installed/);
  const again = cli(['uninstall', '--root', root]);
  assert.equal(again.code, 0);
  assert.match(again.out, /not installed/);
});

test('--dry-run prints the unit and the env file and writes nothing (and needs no root)', () => {
  const root = tmpRoot();
  const r = cli(['install', '--root', root, '--dry-run', '--user', 'alice']);
  assert.equal(r.code, 0, r.err);
  assert.deepEqual(fs.readdirSync(root), []);
  assert.ok(r.out.includes(unitFile(OPTS)));
  assert.match(r.out, /^PORT=8080$/m);
  assert.match(r.out, /robot-cell\.env \(mode 0640\)/);
  // without --root it shows the real paths, also for a user who is not root
  const name = `robot-cell-test-${process.pid}`;
  const d = cli(['install', '--dry-run', '--name', name], { SERVICE_TEST_UID: '1000' });
  assert.equal(d.code, 0, d.err);
  assert.ok(d.out.includes(`# /etc/systemd/system/${name}.service\n`));
  assert.equal(fs.existsSync(`/etc/systemd/system/${name}.service`), false);
});

test('without root, an install to /etc is refused with the sudo command, and writes nothing', () => {
  const name = `robot-cell-test-${process.pid}`;
  const dir = tmpRoot();
  const envPath = path.join(dir, 'cell.env');
  // SERVICE_TEST_UID: the tests may run as root; the check must see a normal user
  const r = cli(['install', '--no-bootstrap', '--name', name, '--environment-file', envPath], { SERVICE_TEST_UID: '1000', PORT: '18080' });
  assert.equal(r.code, 1);
  assert.ok(r.err.includes(`run with sudo: sudo npm run service -- install --no-bootstrap --name ${name} --environment-file ${envPath}`), r.err);
  assert.ok(r.err.includes(`sudo -E ${NODE} ${CLI} install`), r.err); // PORT is set: keep it through sudo
  assert.equal(fs.existsSync(`/etc/systemd/system/${name}.service`), false);
  assert.equal(fs.existsSync(envPath), false);
  // a --root install needs no root
  const root = tmpRoot();
  assert.equal(cli(['install', '--root', root, '--no-bootstrap', '--user', 'alice'], { SERVICE_TEST_UID: '1000' }).code, 0);
  assert.ok(fs.existsSync(path.join(root, 'etc/systemd/system/robot-cell.service')));
});

test('help, and usage errors exit 2 with the usage', () => {
  const h = cli(['help']);
  assert.equal(h.code, 0);
  assert.match(h.out, /Usage: npm run service -- <command>/);
  assert.equal(cli(['install', '--help']).code, 0);
  for (const [args, msg] of [
    [[], /no command given/],
    [['start'], /unknown command: start/],
    [['install', '--force'], /unknown option: --force/],
    [['install', '-f'], /unknown option: -f/],
    [['install', '--name'], /--name needs a value/],
    [['install', '--name', 'a/b'], /not a valid service name/],
    [['install', '--user', 'bad user'], /not a valid user name/],
    [['install', '--environment-file', 'cell.env'], /absolute path/],
    [['install', '--dry-run=yes'], /takes no value/],
    [['status', '--user', 'alice'], /--user does not apply to status/],
    [['uninstall', '--dry-run'], /--dry-run does not apply to uninstall/],
    [['status', 'extra'], /unexpected argument: extra/],
  ]) {
    const r = cli(/** @type {string[]} */ (args));
    assert.equal(r.code, 2, `${args.join(' ')}: ${r.err}`);
    assert.match(r.err, msg);
    assert.match(r.err, /Usage:/);
  }
});

test('the generated unit is well-formed (and passes systemd-analyze verify where it exists)', (t) => {
  const root = tmpRoot();
  assert.equal(cli(['install', '--root', root, '--no-bootstrap', '--user', 'alice']).code, 0);
  const file = path.join(root, 'etc/systemd/system/robot-cell.service');
  const good = checkUnit(file);
  assert.deepEqual(good.problems, []);
  // the check is not blind: a broken copy is caught (by the structure check, and by verify where it runs)
  const bad = path.join(root, 'broken.service');
  fs.writeFileSync(bad, fs.readFileSync(file, 'utf8').replace(/^Restart=on-failure$/m, 'Restart=sometimes').replace(/^KillMode=mixed$/m, 'KilMode=mixed'));
  const problems = checkUnit(bad).problems;
  assert.ok(problems.some((p) => p.includes('KilMode')), problems.join('\n'));
  if (good.verified) {
    assert.ok(problems.some((p) => p.startsWith('systemd-analyze:') && p.includes('sometimes')), problems.join('\n'));
    t.diagnostic('systemd-analyze verify ran on the generated unit');
  } else {
    t.diagnostic('systemd-analyze is not installed here: the unit was checked for structure only, not verified');
  }
});
