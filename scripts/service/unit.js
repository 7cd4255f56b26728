// The text of the systemd unit and of its environment file for `npm run service -- install`, as pure functions
// (no file system, no process state): scripts/service.js gathers the inputs and writes the results.
import path from 'node:path';
import { readEnv } from '../../bff/src/core/config/env.js';

export const DEFAULT_NAME = 'robot-cell';
export const UNIT_DIR = '/etc/systemd/system';
export const DEFAULT_ENV_FILE = '/etc/robot-cell/robot-cell.env';
export const DESCRIPTION = 'Robot cell web UI: roscore, the ROS side, the simulated UR5 cell and the BFF (scripts/stack.js)';

/**
 * The variables of the environment file. `core`: the contract of DESIGN.md, written with the value in effect at
 * install time (USERS_FILE only when it is not the default under DATA_DIR, so that moving DATA_DIR moves it);
 * the others are written only when set, otherwise commented out. `dflt`: the default value, `note`: the default
 * when it is not a value.
 * @typedef {{name: string, meaning: string, dflt: string, note?: string, core: boolean}} EnvVar
 * @type {EnvVar[]}
 */
export const ENV_VARS = [
  { name: 'PORT', meaning: 'BFF HTTP port', dflt: '8080', core: true },
  { name: 'TLS_PORT', meaning: 'BFF HTTPS port, for phones and tablets', dflt: '8443', core: true },
  { name: 'ROS_MASTER_URI', meaning: 'ROS master; the stack starts roscore there unless one answers', dflt: 'http://127.0.0.1:11311', core: true },
  { name: 'ROSBRIDGE_PORT', meaning: 'our rosbridge server, bound to 127.0.0.1 only', dflt: '9090', core: true },
  { name: 'CELL_CONFIG', meaning: 'the cell file', dflt: '', note: '<repo>/config/demo-cell.yaml', core: true },
  { name: 'DATA_DIR', meaning: 'runtime state: users, session key, audit log, CSV, routines, backups, ROS logs; the service user must own it', dflt: '', note: '<repo>/.data', core: true },
  { name: 'USERS_FILE', meaning: 'the users file, scrypt hashes only', dflt: '', note: '$DATA_DIR/users.json', core: true },
  { name: 'UR_HOST', meaning: 'the UR controller, or the address the simulated controller listens on', dflt: '127.0.0.1', core: true },
  { name: 'UR_HOSTS', meaning: 'per motion group, e.g. "left=10.0.0.2,right=10.0.0.3": overrides the hosts of the cell file', dflt: '', note: 'manual.groups[].host of the cell file', core: false },
  { name: 'UR_SIM', meaning: '0: do not start the simulated cell (a real UR at UR_HOST)', dflt: '1', core: false },
  { name: 'SIM_ARGS', meaning: 'extra options for the simulated cell, e.g. "--no-cameras"', dflt: '', note: 'none', core: false },
  { name: 'TLS_CERT', meaning: 'your own certificate (PEM file) for the HTTPS port', dflt: '', note: 'a local CA in $DATA_DIR/tls', core: false },
  { name: 'TLS_KEY', meaning: 'the key of TLS_CERT (PEM file)', dflt: '', note: 'a local CA in $DATA_DIR/tls', core: false },
  { name: 'USB_ROOTS', meaning: 'colon-separated mount roots where USB drives appear', dflt: '', note: 'database.usb_roots of the cell file', core: false },
  { name: 'SESSION_TTL_S', meaning: 'session token lifetime in seconds', dflt: '1800', core: false },
  { name: 'LIVENESS_TIMEOUT_S', meaning: 'a BFF that does not answer /api/health this long is killed and restarted; 0: off', dflt: '30', core: false },
  { name: 'BFF_HOST', meaning: 'address the BFF listens on', dflt: '0.0.0.0', core: false },
];

/**
 * The settings in effect for a process environment, as the stack would see them (bff/src/core/config/env.js).
 * @param {Record<string, string | undefined>} environ
 * @returns {(EnvVar & {value: string | undefined})[]}
 */
export function effectiveSettings(environ) {
  const e = readEnv(environ);
  /** @type {Record<string, string | undefined>} */
  const core = {
    PORT: String(e.port),
    TLS_PORT: String(e.tlsPort),
    ROS_MASTER_URI: e.rosMasterUri,
    ROSBRIDGE_PORT: String(e.rosbridgePort),
    CELL_CONFIG: e.cellConfig,
    DATA_DIR: e.dataDir,
    USERS_FILE: environ.USERS_FILE && e.usersFile !== path.join(e.dataDir, 'users.json') ? e.usersFile : undefined,
    UR_HOST: environ.UR_HOST || '127.0.0.1',
  };
  return ENV_VARS.map((v) => ({ ...v, value: v.core ? core[v.name] : (environ[v.name] || undefined) }));
}

/** @param {string} what @param {string} s */
function oneLine(what, s) {
  if (typeof s !== 'string' || s === '' || /[\n\r\0]/.test(s)) throw new Error(`${what}: not a one-line value: ${JSON.stringify(s)}`);
  return s;
}

/** @param {string} what @param {string} p */
function absolute(what, p) {
  oneLine(what, p);
  if (!path.isAbsolute(p)) throw new Error(`${what} must be an absolute path: ${p}`);
  return path.normalize(p);
}

/** A value where systemd expands specifiers (`%n`): a literal % is `%%`. */
const specifiers = (s) => s.replace(/%/g, '%%');

/** One ExecStart= word: quoted when needed, `%` and `$` escaped (specifiers and variable expansion). */
export function execWord(s) {
  oneLine('ExecStart argument', s);
  let w = s;
  if (/[\s"'\\;]/.test(w)) w = `"${w.replace(/[\\"]/g, '\\$&')}"`;
  return w.replace(/%/g, '%%').replace(/\$/g, '$$$$');
}

/**
 * The unit.
 * @param {{repoRoot: string, nodePath: string, user: string, envFile: string, name?: string, description?: string}} o
 * @returns {string}
 */
export function unitFile(o) {
  const repo = absolute('repository root', o.repoRoot);
  const node = absolute('node path', o.nodePath);
  const envFile = absolute('env file', o.envFile);
  const user = oneLine('user', o.user);
  if (!/^[A-Za-z_][A-Za-z0-9_.-]*\$?$/.test(user)) throw new Error(`not a valid user name: ${user}`);
  const description = specifiers(oneLine('description', o.description || DESCRIPTION));
  const name = serviceName(o.name || DEFAULT_NAME);
  return `# Written by \`npm run service -- install\` (scripts/service.js); a new install overwrites it.
# Settings go in ${specifiers(envFile)} (kept across installs). Docs: docs/service.md.
[Unit]
Description=${description}
Documentation=file://${specifiers(encodeURI(path.join(repo, 'docs/service.md')))}
After=network-online.target
Wants=network-online.target

[Service]
Type=simple
User=${user}
WorkingDirectory=${specifiers(repo)}
EnvironmentFile=${specifiers(envFile)}
ExecStart=${execWord(node)} ${execWord(path.join(repo, 'scripts/stack.js'))}
# The supervisor restarts crashed children itself and exits 1 when one keeps crashing: systemd then restarts
# the whole stack. Exit 2 is a configuration error (cell or users file): restarting cannot help, fix it.
Restart=on-failure
RestartSec=5
RestartPreventExitStatus=2
# SIGINT is the supervisor's Ctrl-C: it stops every process of the stack within 5 s; whatever is left after
# that gets SIGKILL (KillMode=mixed: the signal goes to the supervisor, the final SIGKILL to the whole unit).
KillSignal=SIGINT
KillMode=mixed
TimeoutStopSec=15
StandardOutput=journal
StandardError=journal
SyslogIdentifier=${name}
# Who gets the CPU first (docs/service.md, "Priorities"): the motion path (the arm drivers, the simulated
# controllers) raises itself to nice -10, which LimitNICE allows the service user; deferrable work (video, the
# recorder, graph and log queries, the sim's renderer) lowers itself to nice 10. The cell as a whole weighs ten
# times a default service for CPU and I/O (a kiosk browser, an update), so the robot never pays for a screen.
LimitNICE=-10
CPUWeight=1000
IOWeight=1000

[Install]
WantedBy=multi-user.target
`;
}

/** A value in a systemd EnvironmentFile: bare when safe, else double-quoted with \ " ` $ escaped. */
export function envValue(s) {
  if (/[\n\r\0]/.test(s)) throw new Error(`not a one-line value: ${JSON.stringify(s)}`);
  return /^[A-Za-z0-9_@%+=:,./-]*$/.test(s) ? s : `"${s.replace(/[\\"`$]/g, '\\$&')}"`;
}

/**
 * The environment file: the contract's variables with the values in effect at install time, the optional ones
 * set when they were set, otherwise commented out; each with its meaning and default.
 * @param {{settings: ReturnType<typeof effectiveSettings>, name?: string, repoRoot: string}} o
 * @returns {string}
 */
export function envFile(o) {
  const name = o.name || DEFAULT_NAME;
  const lines = [
    `# Settings of the ${name} service (systemd EnvironmentFile: KEY=value, no shell expansion).`,
    '# Written once by `npm run service -- install`, with the settings in effect then; never overwritten.',
    `# After a change: sudo systemctl restart ${name}. Defaults: README.md, "Contracts". Docs: docs/service.md.`,
    `# <repo> = ${o.repoRoot}`,
  ];
  for (const s of o.settings) {
    lines.push('', `# ${s.meaning} (default: ${s.note || s.dflt})`);
    lines.push(s.value !== undefined ? `${s.name}=${envValue(s.value)}` : `#${s.name}=${envValue(s.dflt)}`);
  }
  return `${lines.join('\n')}\n`;
}

/**
 * Key=value lines of a unit or an env file (comments and sections skipped, the last one wins, quotes removed).
 * @param {string} text
 * @returns {Record<string, string>}
 */
export function parseKeyValues(text) {
  /** @type {Record<string, string>} */
  const out = {};
  for (const raw of text.split('\n')) {
    const line = raw.trim();
    if (!line || line.startsWith('#') || line.startsWith(';') || line.startsWith('[')) continue;
    const i = line.indexOf('=');
    if (i <= 0) continue;
    let v = line.slice(i + 1).trim();
    if (v.length >= 2 && v.startsWith('"') && v.endsWith('"')) v = v.slice(1, -1).replace(/\\(.)/g, '$1');
    out[line.slice(0, i).trim()] = v;
  }
  return out;
}

/**
 * Where the files go. `root` (tests, images) prefixes every path written; the unit names the unprefixed ones.
 * @param {{name: string, envFile: string, root?: string}} o
 */
export function servicePaths(o) {
  const prefix = (p) => (o.root ? path.join(path.resolve(o.root), p) : p);
  const unit = path.join(UNIT_DIR, `${o.name}.service`);
  return { unit, unitWritten: prefix(unit), envFile: o.envFile, envWritten: prefix(o.envFile) };
}

/** A valid service name (without `.service`): letters, digits, `_ . : -`; no templates. */
export function serviceName(s) {
  const name = s.endsWith('.service') ? s.slice(0, -'.service'.length) : s;
  if (!/^[A-Za-z0-9][A-Za-z0-9_.:-]{0,200}$/.test(name)) throw new Error(`not a valid service name: ${s}`);
  return name;
}
