// The audit log's hash chain: AuditLog writes it (across rotations, resuming after a restart), verify.js catches
// altered, removed, inserted and torn entries and a removed tail, and the CLI reports them with exit codes.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { AuditLog } from '../../src/core/audit/audit-log.js';
import { entryHash, GENESIS } from '../../src/core/audit/chain.js';
import { readAuditDir, verifyAuditLog } from '../../src/core/audit/verify.js';
import { tempDir } from '../helpers.js';

const entry = (i) => ({ user: 'u', role: 'r', ip: null, op: 'x', target: String(i), outcome: /** @type {'ok'} */ ('ok') });

/** A log of `n` entries in files of about 5 entries each, 3 rotated files kept (so the oldest were dropped). */
function writeLog(n = 25, dir = tempDir()) {
  const log = new AuditLog({ dir, maxBytes: 1400, keep: 3 });
  for (let i = 0; i < n; i++) log.record(entry(i));
  return { dir, log };
}

const verify = (dir) => verifyAuditLog(readAuditDir(dir));
const read = (dir, name) => fs.readFileSync(path.join(dir, name), 'utf8').split('\n').filter(Boolean);
const write = (dir, name, lines) => fs.writeFileSync(path.join(dir, name), lines.map((l) => `${l}\n`).join(''));

/** Where the entry with this seq is: file name and 1-based line. */
function locate(dir, seq) {
  for (const name of ['audit.log', 'audit.log.1', 'audit.log.2', 'audit.log.3']) {
    if (!fs.existsSync(path.join(dir, name))) continue;
    const i = read(dir, name).findIndex((l) => JSON.parse(l).seq === seq);
    if (i >= 0) return { name, line: i + 1 };
  }
  throw new Error(`seq ${seq} not found`);
}

/** Applies fn to the lines of a file and writes them back. */
function edit(dir, name, fn) {
  const lines = read(dir, name);
  write(dir, name, fn(lines) ?? lines);
}

/** @param {ReturnType<typeof verify>} v */
function assertProblem(v, kind, name, line, seq, message) {
  assert.equal(v.ok, false, v.summary);
  assert.equal(v.problem.kind, kind, v.summary);
  assert.equal(v.problem.file, name, v.summary);
  assert.equal(v.problem.line, line, v.summary);
  assert.equal(v.problem.seq, seq, v.summary);
  if (message) assert.match(v.problem.text, message);
}

test('an untouched log, rotated with the oldest file dropped, verifies intact; query hides the chain fields', () => {
  const { dir, log } = writeLog();
  assert.ok(fs.existsSync(path.join(dir, 'audit.log.3')) && !fs.existsSync(path.join(dir, 'audit.log.4')));
  const v = verify(dir);
  assert.equal(v.ok, true, v.summary);
  assert.equal(v.problem, null);
  assert.equal(v.lastSeq, 25);
  assert.ok(v.firstSeq > 1, 'the oldest entries were rotated away');
  assert.equal(v.entries, 25 - v.firstSeq + 1);
  assert.deepEqual(v.files, ['audit.log.3', 'audit.log.2', 'audit.log.1', 'audit.log']);
  assert.match(v.summary, new RegExp(`^audit log intact: ${v.entries} entries, seq ${v.firstSeq}\\.\\.25, files audit\\.log\\.3, audit\\.log\\.2, audit\\.log\\.1, audit\\.log; chain starts at seq ${v.firstSeq} in audit\\.log\\.3 \\(older entries rotated away`));
  assert.doesNotMatch(v.summary, /\n/);

  // Every entry chains to the one before, across the file boundaries.
  const all = ['audit.log.3', 'audit.log.2', 'audit.log.1', 'audit.log'].flatMap((n) => read(dir, n)).map((l) => JSON.parse(l));
  for (let i = 1; i < all.length; i++) {
    assert.equal(all[i].seq, all[i - 1].seq + 1);
    assert.equal(all[i].prev, all[i - 1].hash);
    assert.equal(all[i].hash, entryHash(all[i]));
  }
  assert.deepEqual(JSON.parse(fs.readFileSync(path.join(dir, 'audit.head'), 'utf8')), { seq: 25, hash: all.at(-1).hash });

  const q = log.query({ limit: 3 });
  assert.deepEqual(q.entries.map((e) => e.seq), [25, 24, 23]);
  assert.deepEqual(Object.keys(q.entries[0]).sort(), ['ip', 'op', 'outcome', 'role', 'seq', 'target', 'time', 'user']);
  assert.equal(q.entries[0].target, '24');
});

test('the first chain of a fresh log starts at seq 1 on the genesis hash', () => {
  const { dir } = writeLog(3);
  const first = JSON.parse(read(dir, 'audit.log')[0]);
  assert.equal(first.seq, 1);
  assert.equal(first.prev, GENESIS);
  const v = verify(dir);
  assert.equal(v.ok, true);
  assert.match(v.summary, /^audit log intact: 3 entries, seq 1\.\.3, files audit\.log; chain starts at seq 1 in audit\.log \(its beginning\)$/);
});

test('an altered field is caught at its line', () => {
  const { dir } = writeLog();
  const { name, line } = locate(dir, 17);
  edit(dir, name, (lines) => { lines[line - 1] = lines[line - 1].replace('"outcome":"ok"', '"outcome":"denied"'); });
  assertProblem(verify(dir), 'altered', name, line, 17, /: altered: hash does not match its content$/);
});

test('an entry rewritten with a recomputed hash is caught by the next entry', () => {
  const { dir } = writeLog();
  const { name, line } = locate(dir, 17);
  edit(dir, name, (lines) => {
    const e = JSON.parse(lines[line - 1]);
    e.user = 'someone-else';
    e.hash = entryHash(e);
    lines[line - 1] = JSON.stringify(e);
  });
  assertProblem(verify(dir), 'altered', name, line, 17, /altered: rewritten with a recomputed hash \(the next entry, seq 18/);
});

test('a line removed in the middle is caught where the seq jumps', () => {
  const { dir } = writeLog();
  const gone = locate(dir, 17);
  const next = locate(dir, 18);
  assert.equal(gone.name, next.name, 'the test removes a line inside one file');
  edit(dir, gone.name, (lines) => lines.filter((_, i) => i !== gone.line - 1));
  assertProblem(verify(dir), 'removed', next.name, next.line - 1, 18, /^audit\.log\.\d line \d+ \(seq 18\): removed: seq jumps from 16 to 18 \(1 entry missing\)$/);
});

test('a forged line with a self-consistent hash is caught as inserted, whatever seq it claims', () => {
  for (const claimed of [18, 999]) {
    const { dir } = writeLog();
    const { name, line } = locate(dir, 17);
    edit(dir, name, (lines) => {
      const before = JSON.parse(lines[line - 1]);
      const forged = { seq: claimed, time: before.time, user: 'admin', role: 'admin', ip: null, op: 'login', outcome: 'ok', prev: before.hash };
      lines.splice(line, 0, JSON.stringify({ ...forged, hash: entryHash(forged) }));
    });
    assertProblem(verify(dir), 'inserted', name, line + 1, claimed, /inserted: not part of the chain/);
  }
});

test('a removed tail is caught by the head file', () => {
  const { dir } = writeLog();
  edit(dir, 'audit.log', (lines) => lines.slice(0, -3));
  const v = verify(dir);
  assert.equal(v.ok, false);
  assert.equal(v.problem.kind, 'removed');
  assert.match(v.problem.text, /^tail removed: the head says seq 25, the log ends at 22 \(audit\.log line \d+\)$/);

  // Removing the head too is reported, not taken as intact.
  fs.rmSync(path.join(dir, 'audit.head'));
  assert.equal(verify(dir).problem.kind, 'head');
  assert.match(verify(dir).summary, /audit\.head is missing/);
});

test('the last entry rewritten with a recomputed hash is caught by the head', () => {
  const { dir } = writeLog();
  let n;
  edit(dir, 'audit.log', (lines) => {
    const e = JSON.parse(lines.at(-1));
    e.detail = 'nothing to see';
    e.hash = entryHash(e);
    lines[lines.length - 1] = JSON.stringify(e);
    n = lines.length;
  });
  assertProblem(verify(dir), 'altered', 'audit.log', n, 25, /does not match the head/);
});

test('an entry appended after the head is caught as inserted', () => {
  const { dir } = writeLog();
  let n;
  edit(dir, 'audit.log', (lines) => {
    const last = JSON.parse(lines.at(-1));
    const forged = { seq: 26, time: last.time, user: 'x', role: 'x', ip: null, op: 'x', outcome: 'ok', prev: last.hash };
    lines.push(JSON.stringify({ ...forged, hash: entryHash(forged) }));
    n = lines.length;
  });
  assertProblem(verify(dir), 'inserted', 'audit.log', n, 26, /after the head \(seq 25\)/);
});

test('tampering across a rotation boundary is caught in the right file', () => {
  // The last entry of audit.log.1 removed: the first entry of audit.log no longer chains.
  let { dir } = writeLog();
  const lastOf1 = read(dir, 'audit.log.1').length;
  const seqLast = JSON.parse(read(dir, 'audit.log.1').at(-1)).seq;
  edit(dir, 'audit.log.1', (lines) => lines.slice(0, -1));
  assertProblem(verify(dir), 'removed', 'audit.log', 1, seqLast + 1, new RegExp(`removed: seq jumps from ${seqLast - 1} to ${seqLast + 1} \\(1 entry missing, between audit\\.log\\.1 and audit\\.log\\)`));

  // The last entry of audit.log.1 rewritten with a recomputed hash: caught by the first entry of audit.log.
  ({ dir } = writeLog());
  edit(dir, 'audit.log.1', (lines) => {
    const e = JSON.parse(lines.at(-1));
    e.outcome = 'denied';
    e.hash = entryHash(e);
    lines[lines.length - 1] = JSON.stringify(e);
  });
  assertProblem(verify(dir), 'altered', 'audit.log.1', lastOf1, seqLast, /next entry, seq \d+ at audit\.log line 1,/);

  // A whole rotated file removed (and the others renamed to close the gap).
  ({ dir } = writeLog());
  const firstOf1 = JSON.parse(read(dir, 'audit.log.1')[0]).seq;
  fs.rmSync(path.join(dir, 'audit.log.1'));
  fs.renameSync(path.join(dir, 'audit.log.2'), path.join(dir, 'audit.log.1'));
  fs.renameSync(path.join(dir, 'audit.log.3'), path.join(dir, 'audit.log.2'));
  assertProblem(verify(dir), 'removed', 'audit.log', 1, seqLast + 1, new RegExp(`seq jumps from ${firstOf1 - 1} to ${seqLast + 1}`));
});

test('a torn last line is cut off at start, the cut recorded in the chain; the chain resumes after the last valid entry', () => {
  const { dir } = writeLog();
  const fragment = '{"seq":26,"time":"2026-01-0';
  fs.appendFileSync(path.join(dir, 'audit.log'), fragment);
  const n = read(dir, 'audit.log').length;
  assertProblem(verify(dir), 'torn', 'audit.log', n, null, /^audit\.log line \d+: torn: incomplete last line/);

  const log = new AuditLog({ dir, maxBytes: 100000, keep: 3 });
  assert.equal(log.seq, 26, 'the repair is entry 26');
  const lines = read(dir, 'audit.log');
  assert.equal(lines.length, n, 'the fragment is gone, the repair entry in its place');
  const repair = JSON.parse(lines.at(-1));
  assert.deepEqual({ seq: repair.seq, op: repair.op, target: repair.target, outcome: repair.outcome, user: repair.user },
    { seq: 26, op: 'audit.torn_write', target: 'audit.log', outcome: 'failed', user: null });
  assert.match(repair.detail, new RegExp(`^cut ${Buffer.byteLength(fragment)} bytes: the incomplete last line of audit\\.log`));
  log.record(entry('after'));
  assert.equal(JSON.parse(read(dir, 'audit.log').at(-1)).target, 'after');
  const v = verify(dir);
  assert.equal(v.ok, true, v.summary);
  assert.equal(v.lastSeq, 27);
  assert.deepEqual(v.repairs, [{ kind: 'torn_write', file: 'audit.log', line: n, seq: 26, detail: repair.detail }]);
  assert.match(v.summary, new RegExp(`^audit log intact: .*; 1 torn write repaired at start \\(seq 26 in audit\\.log line ${n}: cut ${Buffer.byteLength(fragment)} bytes`));
  assert.doesNotMatch(v.summary, /\n/);

  // Nothing more to repair at the next start.
  assert.equal(new AuditLog({ dir, maxBytes: 100000, keep: 3 }).seq, 27);
  assert.equal(read(dir, 'audit.log').length, n + 1);
});

test('a torn last line in a file of its own, and one only missing its newline', () => {
  // The whole current file is a fragment (a crash in the first write after a rotation): cut to empty.
  let { dir, log } = writeLog(12);
  log.rotate();
  fs.writeFileSync(path.join(dir, 'audit.log'), '{"seq":13,"ti');
  log = new AuditLog({ dir, maxBytes: 1400, keep: 3 });
  assert.equal(log.seq, 13);
  assert.equal(JSON.parse(read(dir, 'audit.log')[0]).op, 'audit.torn_write');
  assert.equal(verify(dir).ok, true, verify(dir).summary);

  // A complete entry whose newline did not make it: ended, not cut, and nothing recorded.
  ({ dir } = writeLog(7));
  const text = fs.readFileSync(path.join(dir, 'audit.log'), 'utf8');
  fs.writeFileSync(path.join(dir, 'audit.log'), text.slice(0, -1));
  log = new AuditLog({ dir, maxBytes: 100000, keep: 3 });
  assert.equal(log.seq, 7);
  assert.equal(fs.readFileSync(path.join(dir, 'audit.log'), 'utf8'), text);
  const v = verify(dir);
  assert.equal(v.ok, true, v.summary);
  assert.deepEqual(v.repairs, []);
});

test('the repair at start touches no complete line: tampering stays visible, also after a repaired torn line', () => {
  // A tampered line in the middle, then a torn last line: the torn line is repaired, the tamper still fails.
  let { dir } = writeLog();
  let at = locate(dir, 23);
  edit(dir, at.name, (lines) => { lines[at.line - 1] = lines[at.line - 1].replace('"u"', '"v"'); });
  fs.appendFileSync(path.join(dir, 'audit.log'), '{"seq":26,"ti');
  new AuditLog({ dir, maxBytes: 100000, keep: 3 });
  assertProblem(verify(dir), 'altered', at.name, at.line, 23, /hash does not match its content/);

  // A complete last line that fails the chain is left as it is (and not taken for a lagging head either).
  ({ dir } = writeLog());
  const before = fs.readFileSync(path.join(dir, 'audit.log'), 'utf8');
  edit(dir, 'audit.log', (lines) => { lines[lines.length - 1] = lines.at(-1).replace('"u"', '"v"'); });
  const tampered = fs.readFileSync(path.join(dir, 'audit.log'), 'utf8');
  assert.notEqual(tampered, before);
  let log = new AuditLog({ dir, maxBytes: 100000, keep: 3 });
  assert.equal(fs.readFileSync(path.join(dir, 'audit.log'), 'utf8'), tampered);
  assertProblem(verify(dir), 'altered', 'audit.log', read(dir, 'audit.log').length, 25, /hash does not match its content/);

  // Tampering after a repaired torn line is caught.
  ({ dir } = writeLog());
  fs.appendFileSync(path.join(dir, 'audit.log'), '{"seq":26,"ti');
  log = new AuditLog({ dir, maxBytes: 100000, keep: 3 });
  log.record(entry('a'));
  log.record(entry('b'));
  const n = read(dir, 'audit.log').length;
  edit(dir, 'audit.log', (lines) => { lines[n - 1] = lines[n - 1].replace('"b"', '"c"'); });
  assertProblem(verify(dir), 'altered', 'audit.log', n, 28);

  // A torn line ended with a newline by an older BFF is a complete line now: left alone, still reported as torn.
  ({ dir } = writeLog());
  fs.appendFileSync(path.join(dir, 'audit.log'), '{"seq":26,"ti\n');
  log = new AuditLog({ dir, maxBytes: 100000, keep: 3 });
  log.record(entry('after'));
  const v = verify(dir);
  at = { name: 'audit.log', line: read(dir, 'audit.log').length - 1 };
  assertProblem(v, 'torn', 'audit.log', at.line, null, /torn: not a complete entry \(an interrupted write; the chain runs on around it\)/);
  assert.equal(v.lastSeq, 26);
});

test('a head left behind by a crash between an entry and its head is moved on at start, recorded in the chain', () => {
  const { dir, log } = writeLog();
  const headFile = path.join(dir, 'audit.head');
  const head = fs.readFileSync(headFile);
  log.record(entry('x'));
  log.record(entry('y'));
  fs.writeFileSync(headFile, head); // as if the head updates of 26 and 27 never reached the disk
  assertProblem(verify(dir), 'inserted', 'audit.log', read(dir, 'audit.log').length - 1, 26, /after the head \(seq 25\)/);

  const again = new AuditLog({ dir, maxBytes: 100000, keep: 3 });
  assert.equal(again.seq, 28);
  const repair = JSON.parse(read(dir, 'audit.log').at(-1));
  assert.equal(repair.op, 'audit.head_behind');
  assert.match(repair.detail, /^the head said seq 25, the log ran on to seq 27/);
  const v = verify(dir);
  assert.equal(v.ok, true, v.summary);
  assert.deepEqual(v.repairs.map((r) => [r.kind, r.seq]), [['head_behind', 28]]);
  assert.match(v.summary, /; 1 head left behind repaired at start \(seq 28 in audit\.log line \d+: the head said seq 25/);

  // Entries past the head that do not chain on from it are not taken over: verify still reports them.
  const other = writeLog().dir;
  edit(other, 'audit.log', (lines) => {
    const last = JSON.parse(lines.at(-1));
    const forged = { seq: 26, time: last.time, user: 'x', role: 'x', ip: null, op: 'x', outcome: 'ok', prev: 'f'.repeat(64) };
    lines.push(JSON.stringify({ ...forged, hash: entryHash(forged) }));
  });
  new AuditLog({ dir: other, maxBytes: 100000, keep: 3 });
  assert.equal(read(other, 'audit.log').some((l) => JSON.parse(l).op === 'audit.head_behind'), false);
  assert.equal(verify(other).ok, false);
});

test('re-opening resumes the chain: from the current file, from the newest rotated file, and from the head after a removed tail', () => {
  // From the current file.
  let { dir } = writeLog(7);
  let log = new AuditLog({ dir, maxBytes: 1400, keep: 3 });
  assert.equal(log.seq, 7);
  log.record(entry(7));
  assert.equal(verify(dir).ok, true, verify(dir).summary);
  assert.equal(verify(dir).lastSeq, 8);

  // The current file missing: the newest rotated file (the head gone too, so the files are all there is).
  ({ dir, log } = writeLog(12));
  log.rotate();
  fs.rmSync(path.join(dir, 'audit.head'));
  log = new AuditLog({ dir, maxBytes: 1400, keep: 3 });
  assert.equal(log.seq, 12);
  log.record(entry(12));
  let v = verify(dir);
  assert.equal(v.ok, true, v.summary);
  assert.equal(v.lastSeq, 13);

  // An empty current file.
  ({ dir, log } = writeLog(12));
  log.rotate();
  fs.writeFileSync(path.join(dir, 'audit.log'), '');
  log = new AuditLog({ dir, maxBytes: 1400, keep: 3 });
  assert.equal(log.seq, 12);

  // A tail removed while the BFF was stopped: the restart goes on from the head, so the gap stays visible.
  ({ dir } = writeLog());
  edit(dir, 'audit.log', (lines) => lines.slice(0, -2));
  log = new AuditLog({ dir, maxBytes: 1400, keep: 3 });
  assert.equal(log.seq, 25);
  log.record(entry('next'));
  v = verify(dir);
  assert.equal(v.problem.kind, 'removed');
  assert.match(v.problem.text, /seq jumps from 23 to 26/);
});

test('the head is one fixed-size record; a damaged head is reported, ignored at start and rewritten by the next entry', () => {
  const { dir } = writeLog(6);
  const headFile = path.join(dir, 'audit.head');
  assert.equal(fs.statSync(headFile).size, 128);
  assert.equal(fs.statSync(headFile).mode & 0o777, 0o600);
  fs.writeFileSync(headFile, `{"seq":6,"hash":"${'b'.repeat(30)}${' '.repeat(200)}garbage\n`);
  assert.match(verify(dir).problem.text, /^head: audit\.head is damaged/);
  const log = new AuditLog({ dir, maxBytes: 1400, keep: 3 });
  assert.equal(log.seq, 6, 'resumed from the log');
  log.record(entry(6));
  assert.equal(fs.statSync(headFile).size, 128, 'the longer file was cut to size');
  const v = verify(dir);
  assert.equal(v.ok, true, v.summary);
  assert.equal(v.lastSeq, 7);
});

test('entries from before the chain are a legacy prefix; record() starts a new chain after them', () => {
  const dir = tempDir();
  const old = [0, 1, 2].map((i) => JSON.stringify({ time: '2025-01-01T00:00:00.000Z', ...entry(`old${i}`) }));
  write(dir, 'audit.log', old);
  const log = new AuditLog({ dir });
  log.record(entry('new0'));
  log.record(entry('new1'));
  const v = verify(dir);
  assert.equal(v.ok, true, v.summary);
  assert.equal(v.legacy, 3);
  assert.equal(v.entries, 2);
  assert.match(v.summary, /seq 1\.\.2, files audit\.log; chain starts at seq 1 in audit\.log line 4 \(its beginning\); 3 legacy unchained entries before it$/);
  const q = log.query({ limit: 10 });
  assert.deepEqual(q.entries.map((e) => e.target), ['new1', 'new0', 'old2', 'old1', 'old0']);
  assert.equal(q.entries[4].seq, undefined);

  // Only legacy entries: fine, nothing to check yet.
  const legacyOnly = tempDir();
  write(legacyOnly, 'audit.log', old);
  assert.match(verify(legacyOnly).summary, /^audit log intact: 3 legacy unchained entries, no chained entries$/);

  // An unchained entry inside the chain is not legacy.
  edit(dir, 'audit.log', (lines) => { lines.splice(4, 0, old[0]); });
  assertProblem(verify(dir), 'inserted', 'audit.log', 5, null, /an entry without seq\/hash inside the chain/);
});

test('verifyAuditLog is a pure function of the contents', () => {
  assert.equal(verifyAuditLog({ files: [], head: null }).summary, 'audit log intact: 0 entries (no audit log)');
  const v = verifyAuditLog({ files: [], head: `{"seq":5,"hash":"${'a'.repeat(64)}"}` });
  assert.match(v.problem.text, /^tail removed: the head says seq 5, the log has no chained entries$/);
  assert.equal(verifyAuditLog({ files: [{ name: 'audit.log', text: '' }], head: 'garbage' }).problem.kind, 'head');
});

const cli = (args, env = {}) => spawnSync(process.execPath, ['bff/src/cli/audit.js', ...args], {
  cwd: REPO_ROOT, encoding: 'utf8', env: { ...process.env, ...env },
});

test('audit CLI: exit 0 with a one-line summary, 1 with the first problem, 2 on bad arguments', () => {
  const { dir } = writeLog();
  let r = cli(['verify', '--data-dir', dir]);
  assert.equal(r.status, 0, r.stderr);
  assert.match(r.stdout, /^audit log intact: \d+ entries, seq \d+\.\.25, files audit\.log\.3, audit\.log\.2, audit\.log\.1, audit\.log; chain starts at seq \d+ in audit\.log\.3/);
  assert.equal(r.stdout.trim().split('\n').length, 1);

  r = cli(['verify'], { DATA_DIR: dir });
  assert.equal(r.status, 0, 'DATA_DIR is the default');

  const { name, line } = locate(dir, 17);
  edit(dir, name, (lines) => { lines[line - 1] = lines[line - 1].replace('"u"', '"v"'); });
  r = cli(['verify', `--data-dir=${dir}`]);
  assert.equal(r.status, 1);
  assert.match(r.stdout, new RegExp(`^audit log NOT intact: ${name.replace(/\./g, '\\.')} line ${line} \\(seq 17\\): altered: hash does not match its content$`, 'm'));

  for (const bad of [[], ['bogus'], ['verify', '--data-dir'], ['verify', '--frobnicate'], ['verify', '--data-dir', path.join(dir, 'nope')]]) {
    r = cli(bad);
    assert.equal(r.status, 2, `${bad.join(' ')}: ${r.stdout}${r.stderr}`);
    assert.match(r.stderr, /usage|no such directory/);
  }
  r = cli(['help']);
  assert.equal(r.status, 0);
  assert.match(r.stdout, /npm run audit -- verify \[--data-dir DIR\]/);
});

test('audit CLI: a repaired torn write passes (exit 0) and is reported', () => {
  const { dir } = writeLog();
  fs.appendFileSync(path.join(dir, 'audit.log'), '{"seq":26,"time":"2026');
  let r = cli(['verify', '--data-dir', dir]);
  assert.equal(r.status, 1, 'before the BFF starts, the torn line is reported');
  assert.match(r.stdout, /torn: incomplete last line/);
  new AuditLog({ dir, maxBytes: 100000, keep: 3 });
  r = cli(['verify', '--data-dir', dir]);
  assert.equal(r.status, 0, r.stdout + r.stderr);
  assert.match(r.stdout, /^audit log intact: .*; 1 torn write repaired at start \(seq 26 in audit\.log line \d+: cut 22 bytes/);
});
