#!/usr/bin/env node
// `npm run service -- install|uninstall|status|help`: run the stack at boot on the robot PC as a systemd service.
// The unit and env file texts come from scripts/service/unit.js; this file gathers the inputs, writes the files
// and calls systemctl (only when systemd runs: PID 1 is systemd). See docs/service.md.
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { REPO_ROOT } from '../bff/src/core/config/env.js';
import {
  DEFAULT_ENV_FILE, DEFAULT_NAME, ENV_VARS, UNIT_DIR, effectiveSettings, envFile, parseKeyValues, serviceName,
  servicePaths, unitFile,
} from './service/unit.js';

const SCRIPT = path.join(REPO_ROOT, 'scripts/service.js');
const USAGE = `Usage: npm run service -- <command> [options]   (as root: sudo npm run service -- install)

Commands:
  install     write the systemd unit and the env file, run the bootstrap once, then enable and start the service
  uninstall   stop and disable the service and remove the unit (the env file and DATA_DIR are kept)
  status      the unit file, its ExecStart and env file, and \`systemctl status\` when systemd runs
  help        this text

Options:
  --name NAME               service name (default ${DEFAULT_NAME}: ${UNIT_DIR}/${DEFAULT_NAME}.service)
  --user NAME               install: the user the stack runs as (default: SUDO_USER under sudo, else the current user)
  --environment-file PATH   the unit's EnvironmentFile (default ${DEFAULT_ENV_FILE}; created once, never overwritten)
  --no-bootstrap            install: do not run \`bash scripts/bootstrap.sh\` first
  --dry-run                 install: print the unit and the env file, write nothing
  --root DIR                prefix every path written with DIR and never call systemctl (tests, images; env SERVICE_ROOT)

Docs: docs/service.md`;

// Not `--env-file`: Node 20 takes that for its own option wherever it appears on the command line.
const OPTIONS = {
  install: ['name', 'user', 'environment-file', 'root', 'dry-run', 'no-bootstrap'],
  uninstall: ['name', 'environment-file', 'root'],
  status: ['name', 'environment-file', 'root'],
  help: [],
};
const FLAGS = new Set(['dry-run', 'no-bootstrap']);

class UsageError extends Error {}

/**
 * @param {string[]} argv
 * @returns {{command: string, name: string, user?: string, envFile?: string, root?: string, dryRun: boolean,
 *   bootstrap: boolean, help: boolean}}
 */
function parseArgs(argv, environ = process.env) {
  /** @type {Record<string, string | boolean>} */
  const o = {};
  const positional = [];
  let help = false;
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '-h' || a === '--help') { help = true; continue; }
    if (!a.startsWith('--')) {
      if (a.startsWith('-') && a !== '-') throw new UsageError(`unknown option: ${a}`);
      positional.push(a);
      continue;
    }
    const eq = a.indexOf('=');
    const key = a.slice(2, eq > 0 ? eq : undefined);
    if (!Object.values(OPTIONS).some((l) => l.includes(key))) throw new UsageError(`unknown option: --${key}`);
    if (FLAGS.has(key)) {
      if (eq > 0) throw new UsageError(`--${key} takes no value`);
      o[key] = true;
    } else {
      const v = eq > 0 ? a.slice(eq + 1) : argv[++i];
      if (v === undefined || v === '' || (eq < 0 && v.startsWith('--'))) throw new UsageError(`--${key} needs a value`);
      o[key] = v;
    }
  }
  if (help) return { command: 'help', name: DEFAULT_NAME, dryRun: false, bootstrap: true, help: true };
  if (positional.length === 0) throw new UsageError('no command given');
  const [command, ...extra] = positional;
  if (!(command in OPTIONS)) throw new UsageError(`unknown command: ${command}`);
  if (extra.length) throw new UsageError(`unexpected argument: ${extra[0]}`);
  for (const k of Object.keys(o)) {
    if (!OPTIONS[command].includes(k)) throw new UsageError(`--${k} does not apply to ${command}`);
  }
  let name;
  try { name = serviceName(/** @type {string} */ (o.name ?? DEFAULT_NAME)); } catch (e) { throw new UsageError(e.message); }
  const envPath = /** @type {string | undefined} */ (o['environment-file']);
  if (envPath !== undefined && !path.isAbsolute(envPath)) throw new UsageError(`--environment-file must be an absolute path: ${envPath}`);
  const user = /** @type {string | undefined} */ (o.user);
  if (user !== undefined && !/^[A-Za-z_][A-Za-z0-9_.-]*\$?$/.test(user)) throw new UsageError(`not a valid user name: ${user}`);
  const root = /** @type {string | undefined} */ (o.root) ?? (environ.SERVICE_ROOT || undefined);
  return {
    command, name, user, envFile: envPath, root: root && path.resolve(root),
    dryRun: o['dry-run'] === true, bootstrap: o['no-bootstrap'] !== true, help: false,
  };
}

/** The effective uid; SERVICE_TEST_UID pretends another one (tests of the refusal, run as root). */
function uid() {
  const fake = process.env.SERVICE_TEST_UID;
  return fake !== undefined && fake !== '' ? Number(fake) : process.getuid?.() ?? -1;
}

/** @param {string} name @returns {{name: string, uid: number, gid: number, home: string} | null} */
function account(name) {
  try {
    for (const line of fs.readFileSync('/etc/passwd', 'utf8').split('\n')) {
      const f = line.split(':');
      if (f[0] === name && f.length >= 7) return { name, uid: Number(f[2]), gid: Number(f[3]), home: f[5] };
    }
  } catch { /* no passwd file */ }
  return null;
}

/** The user the stack runs as: --user, else SUDO_USER under sudo, else the current user. */
function serviceUser(o) {
  if (o.user) return o.user;
  const sudoUser = process.env.SUDO_USER;
  if (uid() === 0 && sudoUser && sudoUser !== 'root') return sudoUser;
  return os.userInfo().username;
}

/** An executable on PATH (or in /usr/bin, /bin), or null: systemd's tools exist only where systemd does. */
function which(cmd) {
  const dirs = [...(process.env.PATH || '').split(':'), '/usr/bin', '/bin', '/usr/sbin', '/sbin'].filter(Boolean);
  for (const d of dirs) {
    const p = path.join(d, cmd);
    try { fs.accessSync(p, fs.constants.X_OK); if (fs.statSync(p).isFile()) return p; } catch { /* next */ }
  }
  return null;
}

/** Whether to call systemctl: not with --root, and only where systemd is PID 1 (/run/systemd/system exists). */
function systemd(o) {
  if (o.root) return { running: false, why: `--root ${o.root} is set, so systemctl was not called` };
  if (!fs.existsSync('/run/systemd/system')) {
    return { running: false, why: 'systemd is not running on this machine (no /run/systemd/system), so systemctl was not called' };
  }
  const systemctl = which('systemctl');
  if (!systemctl) return { running: false, why: 'systemctl is not installed, so it was not called' };
  return { running: true, systemctl, why: '' };
}

/** Run a systemd tool, its output on ours; true when it succeeded. */
function run(tool, args, { quiet = false } = {}) {
  if (!quiet) console.log(`$ ${path.basename(tool)} ${args.join(' ')}`);
  const r = spawnSync(tool, args, { stdio: quiet ? 'ignore' : 'inherit' });
  return r.status === 0;
}

const shq = (s) => (/^[\w@%+=:,./-]+$/.test(s) ? s : `'${s.replace(/'/g, `'\\''`)}'`);

/** The refusal when not root, with the command that works. */
function needRoot(argv) {
  const args = argv.map(shq).join(' ');
  const lines = [`${path.basename(SCRIPT)}: writing to /etc/systemd/system needs root.`,
    `run with sudo: sudo npm run service -- ${args}`];
  const secure = ['/usr/local/sbin', '/usr/local/bin', '/usr/sbin', '/usr/bin', '/sbin', '/bin'];
  const direct = `${shq(process.execPath)} ${shq(SCRIPT)} ${args}`;
  if (!secure.includes(path.dirname(process.execPath))) {
    lines.push(`sudo resets PATH and will not find this node (${path.dirname(process.execPath)}); use its full path instead:`,
      `  sudo ${direct}`);
  }
  const set = ENV_VARS.filter((v) => process.env[v.name] !== undefined).map((v) => v.name);
  if (set.length && argv[0] === 'install') {
    lines.push(`sudo drops your environment (${set.join(', ')}); to write those settings into the env file, keep it:`,
      `  sudo -E ${direct}`);
  }
  console.error(lines.join('\n'));
  return 1;
}

/** Write a file atomically (temp file + rename) with a mode. */
function writeAtomic(file, text, mode) {
  fs.mkdirSync(path.dirname(file), { recursive: true, mode: 0o755 });
  const tmp = `${file}.tmp-${process.pid}`;
  fs.writeFileSync(tmp, text, { mode });
  fs.chmodSync(tmp, mode);
  fs.renameSync(tmp, file);
}

function readOrNull(file) {
  try { return fs.readFileSync(file, 'utf8'); } catch { return null; }
}

/** `bash scripts/bootstrap.sh`: as root for apt, as the service user for the rest (so the repo stays theirs). */
function bootstrap(acct) {
  const pathEnv = `${path.dirname(process.execPath)}:${process.env.PATH || '/usr/bin:/bin'}`;
  const script = 'scripts/bootstrap.sh';
  const go = (stages, extra = {}) => {
    console.log(`$ bash ${script} ${stages.join(' ')}`.trimEnd() + (extra.uid !== undefined ? ` (as ${acct.name})` : ''));
    const r = spawnSync('bash', [script, ...stages], { cwd: REPO_ROOT, stdio: 'inherit', ...extra });
    return r.status === 0;
  };
  const asRoot = process.getuid?.() === 0;
  if (!asRoot || !acct || acct.uid === 0) return go([], { env: { ...process.env, PATH: pathEnv } });
  // .state holds the stamps of every stage: make it the user's before root's apt stage would create it.
  const state = path.join(REPO_ROOT, '.state');
  if (!fs.existsSync(state)) { fs.mkdirSync(state); fs.chownSync(state, acct.uid, acct.gid); }
  if (!go(['apt'], { env: { ...process.env, PATH: pathEnv } })) return false;
  const env = { ...process.env, PATH: pathEnv, HOME: acct.home, USER: acct.name, LOGNAME: acct.name };
  for (const k of ['SUDO_USER', 'SUDO_UID', 'SUDO_GID', 'SUDO_COMMAND']) delete env[k];
  return go(['venv', 'npm', 'catkin', 'app'], { env, uid: acct.uid, gid: acct.gid });
}

function install(o, argv) {
  const user = serviceUser(o);
  const envPath = o.envFile || DEFAULT_ENV_FILE;
  const p = servicePaths({ name: o.name, envFile: envPath, root: o.root });
  const unit = unitFile({ repoRoot: REPO_ROOT, nodePath: process.execPath, user, envFile: envPath, name: o.name });
  const envText = envFile({ settings: effectiveSettings(process.env), name: o.name, repoRoot: REPO_ROOT });
  const envExists = fs.existsSync(p.envWritten);
  if (o.dryRun) {
    console.log(`# dry run: nothing is written.\n# ${p.unitWritten}\n${unit}`);
    if (envExists) console.log(`# ${p.envWritten} exists and would be kept as it is.`);
    else console.log(`# ${p.envWritten} (mode 0640)\n${envText}`);
    return 0;
  }
  if (!o.root && uid() !== 0) return needRoot(argv);
  const acct = account(user);
  if (!acct && !o.root) { console.error(`no such user: ${user} (choose one with --user NAME)`); return 1; }
  if (!acct) console.log(`note: user ${user} is not in this machine's /etc/passwd`);
  if (user === 'root') console.log('note: the stack will run as root; a normal user is safer: --user NAME');

  if (o.bootstrap && !bootstrap(acct)) { console.error('the bootstrap failed: nothing was installed'); return 1; }

  const sd = systemd(o);
  const wasActive = sd.running && run(sd.systemctl, ['is-active', '--quiet', `${o.name}.service`], { quiet: true });

  if (envExists) {
    console.log(`kept ${p.envWritten} (it exists; never overwritten)`);
  } else {
    fs.mkdirSync(path.dirname(p.envWritten), { recursive: true, mode: 0o755 });
    fs.writeFileSync(p.envWritten, envText, { mode: 0o640, flag: 'wx' });
    fs.chmodSync(p.envWritten, 0o640);
    // Readable by the service user's group (systemd itself reads it as root).
    if (!o.root && process.getuid?.() === 0 && acct) fs.chownSync(p.envWritten, 0, acct.gid);
    console.log(`wrote ${p.envWritten} (mode 0640): the settings in effect now; edit it, then restart the service`);
  }
  writeAtomic(p.unitWritten, unit, 0o644);
  console.log(`wrote ${p.unitWritten}: ${process.execPath} scripts/stack.js in ${REPO_ROOT} as ${user}`);

  // DATA_DIR must be the user's: create it if the env file names one that does not exist yet.
  const dataDir = parseKeyValues(readOrNull(p.envWritten) ?? '').DATA_DIR;
  if (!o.root && acct && dataDir && path.isAbsolute(dataDir) && !fs.existsSync(dataDir)) {
    fs.mkdirSync(dataDir, { recursive: true, mode: 0o750 });
    if (process.getuid?.() === 0) fs.chownSync(dataDir, acct.uid, acct.gid);
    console.log(`created DATA_DIR ${dataDir} for ${user}`);
  }

  if (!sd.running) {
    console.log(`\n${sd.why}: the service is not enabled or started yet. On the robot PC (systemd running), run:`);
    console.log(`  sudo systemctl daemon-reload\n  sudo systemctl enable --now ${o.name}`);
    return 0;
  }
  if (!run(sd.systemctl, ['daemon-reload']) || !run(sd.systemctl, ['enable', '--now', `${o.name}.service`])) {
    console.error(`systemctl failed; see: systemctl status ${o.name}; journalctl -u ${o.name} -n 50 --no-pager`);
    return 1;
  }
  if (wasActive) {
    console.log(`\n${o.name} was already running and still runs the code it started with; to use the new one:`);
    console.log(`  sudo systemctl restart ${o.name}`);
  } else {
    console.log(`\n${o.name} is enabled (starts at boot) and started.`);
  }
  console.log(`status: npm run service -- status; logs: journalctl -u ${o.name} -f`);
  return 0;
}

/** The env file of an installed unit: --environment-file, else the unit's EnvironmentFile=, else the default. */
function envFileOf(o, unitText) {
  if (o.envFile) return o.envFile;
  const fromUnit = unitText && parseKeyValues(unitText).EnvironmentFile;
  return fromUnit ? fromUnit.replace(/^-/, '').replace(/%%/g, '%') : DEFAULT_ENV_FILE;
}

function uninstall(o, argv) {
  const unitPaths = servicePaths({ name: o.name, envFile: DEFAULT_ENV_FILE, root: o.root });
  const unitText = readOrNull(unitPaths.unitWritten);
  const p = servicePaths({ name: o.name, envFile: envFileOf(o, unitText), root: o.root });
  if (unitText === null && !fs.existsSync(p.unitWritten)) {
    console.log(`${o.name} is not installed (no ${p.unitWritten}); nothing to do.`);
    return 0;
  }
  if (!o.root && uid() !== 0) return needRoot(argv);
  const sd = systemd(o);
  if (sd.running) run(sd.systemctl, ['disable', '--now', `${o.name}.service`]);
  fs.rmSync(p.unitWritten, { force: true });
  console.log(`removed ${p.unitWritten}`);
  if (sd.running) {
    run(sd.systemctl, ['daemon-reload']);
    run(sd.systemctl, ['reset-failed', `${o.name}.service`], { quiet: true });
  } else {
    console.log(`${sd.why}.`);
  }
  const envText = readOrNull(p.envWritten);
  const dataDir = parseKeyValues(envText ?? '').DATA_DIR || effectiveSettings(process.env).find((s) => s.name === 'DATA_DIR')?.value;
  console.log(`kept: the env file ${p.envWritten}${fs.existsSync(p.envWritten) ? '' : ' (not present)'} and DATA_DIR ${dataDir} `
    + '(users, audit log, routines, backups); remove them by hand if you no longer need them.');
  return 0;
}

function status(o) {
  const unitPaths = servicePaths({ name: o.name, envFile: DEFAULT_ENV_FILE, root: o.root });
  const unitText = readOrNull(unitPaths.unitWritten);
  const p = servicePaths({ name: o.name, envFile: envFileOf(o, unitText), root: o.root });
  const sd = systemd(o);
  if (unitText === null) {
    console.log(`unit file: ${p.unitWritten}: not installed (install: sudo npm run service -- install)`);
  } else {
    const u = parseKeyValues(unitText);
    console.log(`unit file: ${p.unitWritten}: installed`);
    for (const k of ['ExecStart', 'User', 'WorkingDirectory', 'EnvironmentFile']) console.log(`  ${k}=${u[k] ?? '(none)'}`);
  }
  let envState = 'missing (the service cannot start without it: install again to create it)';
  if (fs.existsSync(p.envWritten)) {
    const mode = (fs.statSync(p.envWritten).mode & 0o777).toString(8).padStart(4, '0');
    const text = readOrNull(p.envWritten);
    envState = `exists (mode ${mode})`;
    if (text === null) envState += ', not readable as this user';
    else {
      const kv = parseKeyValues(text);
      envState += `\n  ${ENV_VARS.filter((v) => kv[v.name] !== undefined).map((v) => `${v.name}=${kv[v.name]}`).join('\n  ')}`;
    }
  }
  console.log(`env file: ${p.envWritten}: ${envState}`);
  if (sd.running) {
    console.log('');
    run(sd.systemctl, ['status', '--no-pager', `${o.name}.service`]);
  } else {
    console.log(`${sd.why}: no service state to show.`);
  }
  console.log(`logs: journalctl -u ${o.name} -n 20 --no-pager   (follow: journalctl -u ${o.name} -f)`);
  return unitText === null ? 1 : 0;
}

function main(argv) {
  let o;
  try {
    o = parseArgs(argv);
  } catch (e) {
    if (!(e instanceof UsageError)) throw e;
    console.error(`${path.basename(SCRIPT)}: ${e.message}\n\n${USAGE}`);
    return 2;
  }
  if (o.command === 'help') { console.log(USAGE); return 0; }
  try {
    if (o.command === 'install') return install(o, argv);
    if (o.command === 'uninstall') return uninstall(o, argv);
    return status(o);
  } catch (e) {
    console.error(`${path.basename(SCRIPT)} ${o.command}: ${e.message}`);
    return 1;
  }
}

process.exitCode = main(process.argv.slice(2));
