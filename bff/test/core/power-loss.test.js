// Nothing acknowledged is lost, nothing is left torn: for each kind of durable write the BFF makes (the users file,
// database file replacements with their backups, the audit log), a child process (fixtures/power-loss/writer.js)
// writes version after version through the real module and acks each one once the call has returned; it is
// SIGKILLed after a random number of acks plus a random sub-millisecond delay (0-25 ms for a database replace, which
// takes that long), so mostly in the middle of a write (half the audit kills are aimed inside a multi-megabyte
// append, the only kind a SIGKILL can tear).
// After each kill the file must be exactly the last acked version or the one being written (never torn, never
// older), and the module must start again on what is there (temp files cleaned up, the audit chain verifying).
// The runs go on in the same directory, so every start also meets what the previous kill left.
//
// A SIGKILL leaves the page cache in place, so this proves the order of the writes (every instant's state on disk
// is a valid one); that this state is the one a power loss leaves is the fsync before each ack, traced in the last
// tests.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import fsp from 'node:fs/promises';
import path from 'node:path';
import { spawn, spawnSync } from 'node:child_process';
import { once } from 'node:events';
import { fileURLToPath } from 'node:url';
import { Readable } from 'node:stream';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { UserStore, ensureInitialUsers } from '../../src/core/auth/users.js';
import { DatabaseFiles } from '../../src/features/database/database-files.js';
import { checkContent } from '../../src/features/database/content-check.js';
import { AuditLog } from '../../src/core/audit/audit-log.js';
import { readAuditDir, verifyAuditLog } from '../../src/core/audit/verify.js';
import {
  AUDIT_OPTIONS, DB_CELL, DB_KEEP_BACKUPS, DB_TARGET, auditEntryOf, csvOf, csvVersion, usersOf,
} from '../fixtures/power-loss/versions.js';
import { tempDir } from '../helpers.js';

const WRITER = fileURLToPath(new URL('../fixtures/power-loss/writer.js', import.meta.url));

/** Busy-waits up to `us` microseconds (a timer cannot wait less than a millisecond). @param {number} us */
function spin(us) {
  const until = process.hrtime.bigint() + BigInt(Math.floor(us * 1000));
  while (process.hrtime.bigint() < until) { /* spin */ }
}

/** Kill after this many acks. @param {number} n @returns {(lines: string[]) => boolean} */
const afterAcks = (n) => (lines) => lines.filter((l) => l.startsWith('ack ')).length >= n;
/** Kill inside the next large write (the writer announces it). @type {(lines: string[]) => boolean} */
const inLargeWrite = (lines) => lines.some((l) => l.startsWith('writing '));

/**
 * Starts the writer at version `start` and kills it, 0 to `delayMs` ms after its output first satisfies `when`.
 * @param {string} kind @param {string} dir @param {number} start @param {{when: (lines: string[]) => boolean,
 *   args?: string[], delayMs?: number}} run  when: sees the lines after "ready"; args: more arguments for the writer;
 *   delayMs: 1 by default (a busy wait), more for writes that take longer (a timer)
 * @returns {Promise<{acked: number[], lines: string[]}>} the versions acked before it died
 */
async function writeAndKill(kind, dir, start, { when, args = [], delayMs = 1 }) {
  const child = spawn(process.execPath, [WRITER, kind, dir, String(start), ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  let err = '';
  /** @type {string[]} */
  const lines = [];
  let killed = false;
  child.stderr.on('data', (d) => { err += d; });
  child.stdout.on('data', (d) => {
    out += d;
    const parts = out.split('\n');
    out = parts.pop() ?? '';
    lines.push(...parts);
    const ready = lines.indexOf('ready');
    if (!killed && ready >= 0 && when(lines.slice(ready + 1))) {
      killed = true;
      const delay = Math.random() * delayMs;
      if (delayMs <= 1) {
        spin(delay * 1000);
        child.kill('SIGKILL');
      } else {
        setTimeout(() => child.kill('SIGKILL'), delay);
      }
    }
  });
  const [code, signal] = await once(child, 'close');
  if (out) lines.push(out); // an ack cut short by the kill is no ack
  assert.equal(signal, 'SIGKILL', `the writer must be killed, not stop (exit ${code}): ${err}`);
  const acked = lines.filter((l) => /^ack \d+( \d+)?$/.test(l)).map((l) => Number(l.split(' ')[1]));
  assert.deepEqual(acked, acked.map((_, k) => start + k), 'acked in order');
  return { acked, lines };
}

/**
 * Kills the writer `kills` times; check({k, start, last, inFlight, before}) runs after each kill and returns the
 * version on disk. k: the run; start: its first version; last: the last acked one (null: none acked); inFlight:
 * the one being written when it died; before: the version on disk before this run (null: none).
 * @param {string} kind @param {string} dir @param {number} kills
 * @param {(k: number) => {when: (lines: string[]) => boolean, args?: string[]}} plan  how run k goes
 * @param {(o: {k: number, start: number, last: number|null, inFlight: number, before: number|null, lines: string[]}) => Promise<number|null>|number|null} check
 */
async function killRepeatedly(kind, dir, kills, plan, check) {
  let before = null;
  let start = 0;
  let acks = 0;
  let landed = 0;
  for (let k = 0; k < kills; k++) {
    const { acked, lines } = await writeAndKill(kind, dir, start, plan(k));
    const last = acked.length ? acked.at(-1) : null;
    const inFlight = (last ?? start - 1) + 1;
    const now = await check({ k, start, last, inFlight, before, lines });
    if (now === inFlight) landed++;
    acks += acked.length;
    before = now;
    start = inFlight + 1; // every version is written once, so each one is told apart
  }
  return { acks, landed };
}

/** A random whole number from 0 to n. @param {number} n */
const upTo = (n) => Math.floor(Math.random() * (n + 1));

test('users file: 40 kills while saving, always the last acked or the next version', { timeout: 120_000 }, async (t) => {
  const dir = tempDir('bff-powerloss-users-');
  const file = path.join(dir, 'users.json');
  const text = (v) => JSON.stringify({ version: 1, users: usersOf(v) }, null, 2) + '\n';
  const t0 = Date.now();
  const r = await killRepeatedly('users', dir, 40, () => ({ when: afterAcks(upTo(40)) }), ({ last, inFlight, before }) => {
    const store = new UserStore(file);
    assert.deepEqual(fs.readdirSync(dir).filter((n) => n !== 'users.json'), [], 'no temp file left after a start');
    const listed = store.list(); // loads (throws on a torn file)
    const onDisk = fs.existsSync(file) ? fs.readFileSync(file, 'utf8') : null;
    const allowed = [last ?? before, inFlight];
    const v = allowed.find((x) => (x === null ? onDisk === null : onDisk === text(x)));
    assert.notEqual(v, undefined, `users.json is neither version ${allowed.join(' nor ')}: ${onDisk?.slice(0, 200)}`);
    assert.deepEqual(listed, v === null ? [] : usersOf(v).map(({ username, role }) => ({ username, role })));
    return v;
  });
  t.diagnostic(`40 kills, ${r.acks} acked saves, ${r.landed} kills after the in-flight save had landed, ${Date.now() - t0} ms`);
  fs.rmSync(dir, { recursive: true, force: true });
});

test('database file replacements: 40 kills while replacing; the file and every backup whole, the acked one kept', { timeout: 120_000 }, async (t) => {
  const dir = tempDir('bff-powerloss-db-');
  const dbDir = path.join(dir, 'database');
  const backupDir = path.join(dbDir, '.backups');
  const t0 = Date.now();
  let backupsSeen = 0;
  const r = await killRepeatedly('database', dir, 40, () => ({ when: afterAcks(upTo(10)), delayMs: 25 }), async ({ start, last, inFlight, before }) => {
    const db = new DatabaseFiles({ cell: DB_CELL, dataDir: dir, usbRoots: [], keepBackups: DB_KEEP_BACKUPS });
    for (const d of [dbDir, backupDir]) {
      const temps = fs.existsSync(d) ? fs.readdirSync(d).filter((n) => n.endsWith('.tmp')) : [];
      assert.deepEqual(temps, [], `no temp file left in ${d} after a start`);
    }
    const file = path.join(dbDir, DB_TARGET);
    const onDisk = fs.existsSync(file) ? fs.readFileSync(file) : null;
    const allowed = [last ?? before, inFlight];
    const v = allowed.find((x) => (x === null ? onDisk === null : onDisk?.equals(csvOf(x))));
    assert.notEqual(v, undefined, `${DB_TARGET} is neither version ${allowed.join(' nor ')} (${onDisk?.length} bytes, claims ${onDisk && csvVersion(onDisk)})`);
    if (onDisk) checkContent('.csv', onDisk);
    assert.equal((await db.listTargets())[0].exists, v !== null);

    // Every backup is a whole earlier version; the one the last acked replace made is there.
    const backups = await db.listBackups(DB_TARGET);
    const versions = backups.map((b) => {
      const buf = fs.readFileSync(path.join(backupDir, b.name));
      const bv = csvVersion(buf);
      assert.ok(buf.equals(csvOf(bv)), `backup ${b.name} is torn (${buf.length} bytes, claims version ${bv})`);
      return bv;
    });
    backupsSeen += backups.length;
    // The acked replace with `last` backed up the version before it, if there was one.
    const prior = last === null ? null : last > start ? last - 1 : before;
    if (prior !== null) assert.ok(versions.includes(prior), `the backup of version ${prior}, made by acked version ${last}, is gone: ${versions}`);
    return v;
  });
  t.diagnostic(`40 kills, ${r.acks} acked replaces, ${r.landed} kills after the in-flight replace had landed, ${backupsSeen} backups checked, ${Date.now() - t0} ms`);
  fs.rmSync(dir, { recursive: true, force: true });
});

test('audit log: 40 kills while appending; the acked entry kept, torn writes repaired at start, the chain verifies', { timeout: 120_000 }, async (t) => {
  const dir = tempDir('bff-powerloss-audit-');
  const t0 = Date.now();
  let torn = 0;
  let behind = 0;
  // Every other run writes large entries and is killed inside the first (see auditEntryOf), the others anywhere.
  const large = (k) => k % 2 === 1;
  const plan = (k) => (large(k) ? { when: inLargeWrite, args: ['large'] } : { when: afterAcks(upTo(40)) });
  const r = await killRepeatedly('audit', dir, 40, plan, ({ k, last, inFlight, lines }) => {
    const log = new AuditLog({ dir, ...AUDIT_OPTIONS }); // the start repairs what the kill left
    torn += log.repairs.filter((x) => x.op === 'audit.torn_write').length;
    behind += log.repairs.filter((x) => x.op === 'audit.head_behind').length;
    const files = readAuditDir(dir);
    const v = verifyAuditLog(files);
    assert.equal(v.ok, true, v.summary);
    const entries = new Map();
    for (const f of files.files) {
      for (const l of f.text.split('\n')) if (l) { const e = JSON.parse(l); if (e.op === 'test.write') entries.set(Number(e.target), e); }
    }
    if (last !== null) {
      const e = entries.get(last);
      assert.ok(e, `acked entry ${last} is gone`);
      const ackSeq = Number(lines.filter((l) => l.startsWith('ack ')).at(-1).split(' ')[2]);
      assert.equal(e.seq, ackSeq);
      assert.equal(e.detail, auditEntryOf(last, large(k)).detail);
    }
    const flying = entries.get(inFlight);
    if (flying) assert.equal(flying.detail, auditEntryOf(inFlight, large(k)).detail, 'the in-flight entry is whole or absent');
    return flying ? inFlight : last;
  });
  assert.ok(torn + behind > 0, 'some kills landed between an append and its head, or inside an append');
  const cli = spawnSync(process.execPath, ['bff/src/cli/audit.js', 'verify', '--data-dir', dir], { cwd: REPO_ROOT, encoding: 'utf8' });
  assert.equal(cli.status, 0, cli.stdout + cli.stderr);
  t.diagnostic(`40 kills (20 inside a large write), ${r.acks} acked entries, ${r.landed} kills after the in-flight entry had landed, ${torn} torn writes and ${behind} lagging heads repaired at start, ${Date.now() - t0} ms`);
  t.diagnostic(cli.stdout.trim().slice(0, 400));
  fs.rmSync(dir, { recursive: true, force: true });
});

// The fsync traces: each durable write's system calls in order, with temp-file names as .TMP and times as <time>.
const short = (p) => path.basename(String(p)).replace(/\.\d+\.[0-9a-f]+\.tmp$/, '.TMP').replace(/\.\d{4}-\d\d-\d\dT.*$/, '.<time>');

/**
 * Runs fn with node:fs's synchronous writes traced: "write F", "fsync F" (fsync or fdatasync), "rename A -> B".
 * @param {() => unknown} fn @returns {Promise<string[]>}
 */
async function traceSync(fn) {
  /** @type {string[]} */
  const trace = [];
  const names = new Map();
  const patched = {
    openSync: (orig) => (p, ...a) => { const fd = orig(p, ...a); names.set(fd, short(p)); return fd; },
    writeSync: (orig) => (fd, ...a) => { trace.push(`write ${names.get(fd)}`); return orig(fd, ...a); },
    fsyncSync: (orig) => (fd) => { trace.push(`fsync ${names.get(fd)}`); return orig(fd); },
    fdatasyncSync: (orig) => (fd) => { trace.push(`fsync ${names.get(fd)}`); return orig(fd); },
    renameSync: (orig) => (a, b) => { trace.push(`rename ${short(a)} -> ${short(b)}`); return orig(a, b); },
  };
  const saved = Object.fromEntries(Object.keys(patched).map((k) => [k, fs[k]]));
  for (const [k, wrap] of Object.entries(patched)) fs[k] = wrap(saved[k]);
  try { await fn(); } finally { Object.assign(fs, saved); }
  return trace;
}

test('fsync trace: a users file save is fsync\'ed, renamed into place and its directory fsync\'ed before it returns', async () => {
  const dir = tempDir('bff-fsync-');
  const store = new UserStore(path.join(dir, 'users.json'));
  store.users = usersOf(1);
  assert.deepEqual(await traceSync(() => store.save()), [
    'write .users.json.TMP', 'fsync .users.json.TMP', 'rename .users.json.TMP -> users.json', `fsync ${path.basename(dir)}`,
  ]);
  fs.rmSync(dir, { recursive: true, force: true });
});

test('fsync trace: the first start writes the initial passwords before the users, all users in one write', async () => {
  // A crash between the two then leaves no users file (the next start begins again), never users without passwords.
  const dir = tempDir('bff-fsync-');
  const store = new UserStore(path.join(dir, 'users.json'));
  const trace = await traceSync(() => ensureInitialUsers(store, dir, ['admin', 'operator', 'viewer']));
  assert.deepEqual(trace.filter((x) => x.startsWith('rename')), [
    'rename .initial-passwords.txt.TMP -> initial-passwords.txt', 'rename .users.json.TMP -> users.json',
  ]);
  assert.deepEqual(new UserStore(path.join(dir, 'users.json')).list().map((u) => u.username), ['admin', 'operator', 'viewer']);
  fs.rmSync(dir, { recursive: true, force: true });
});

test('fsync trace: an audit entry is fsync\'ed before record() returns, and before the head is written', async () => {
  const dir = tempDir('bff-fsync-');
  const log = new AuditLog({ dir, ...AUDIT_OPTIONS });
  // The first entry: a new log file and a new head, so their directory entries are made durable too.
  assert.deepEqual(await traceSync(() => log.record(auditEntryOf(1, false))), [
    'write audit.log', 'fsync audit.log', `fsync ${path.basename(dir)}`, 'write audit.head', 'fsync audit.head', `fsync ${path.basename(dir)}`,
  ]);
  // Then one fsync an entry; the head is overwritten in place after it (see audit-log.js).
  assert.deepEqual(await traceSync(() => log.record(auditEntryOf(2, false))), ['write audit.log', 'fsync audit.log', 'write audit.head']);
  fs.rmSync(dir, { recursive: true, force: true });
});

test('fsync trace: a database file replace syncs the new file and the backup, renames each into place and fsyncs their directories before it returns', async () => {
  const dir = tempDir('bff-fsync-');
  /** @type {string[]} */
  const trace = [];
  const names = new Map();
  const probe = await fsp.open(dir, 'r');
  const proto = Object.getPrototypeOf(probe);
  await probe.close();
  const real = { sync: proto.sync, open: fsp.open, rename: fsp.rename };
  proto.sync = function () { trace.push(`sync ${names.get(this.fd)}`); return real.sync.call(this); };
  fsp.open = async (p, ...a) => { const fh = await real.open(p, ...a); names.set(fh.fd, short(p)); return fh; };
  fsp.rename = async (a, b) => { trace.push(`rename ${short(a)} -> ${short(b)}`); return real.rename(a, b); };
  try {
    const db = new DatabaseFiles({ cell: DB_CELL, dataDir: dir, usbRoots: [] });
    await db.replaceFromUpload(DB_TARGET, Readable.from([csvOf(1)]), 'a.csv', {});
    trace.length = 0;
    await db.replaceFromUpload(DB_TARGET, Readable.from([csvOf(2)]), 'a.csv', {});
    assert.deepEqual(trace, [
      `sync .${DB_TARGET}.TMP`, // the new content
      'sync database', // .backups was created: its entry in database
      `sync .${DB_TARGET}.TMP`, `rename .${DB_TARGET}.TMP -> ${DB_TARGET}.<time>`, 'sync .backups', // the old one's backup
      `rename .${DB_TARGET}.TMP -> ${DB_TARGET}`, 'sync database', // the new file in place
    ]);
  } finally {
    Object.assign(proto, { sync: real.sync });
    Object.assign(fsp, { open: real.open, rename: real.rename });
  }
  fs.rmSync(dir, { recursive: true, force: true });
});
