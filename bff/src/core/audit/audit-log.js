// Append-only JSON-lines audit log in DATA_DIR, rotated by size (audit.log, audit.log.1, ... audit.log.N), and
// tamper-evident: every entry is chained to the one before it by a sha256 hash (see chain.js for the format), and
// the chain runs on across rotations (the first entry of a new file chains to the last one of the previous file).
// `npm run audit -- verify` checks it (verify.js).
//
// Durable: record() returns (and the request is answered) only once the entry is on disk (fdatasync, ~0.3 ms on
// the project's machines; audit entries come per command, not per streamed message). A crash or power loss can
// only tear the one entry that was being written, which no one was told about: the next start cuts that
// incomplete last line off and records the cut in the chain (op audit.torn_write), so verify passes and reports it.
// A complete line is never touched at start, however wrong it is: that is for verify to report.
//
// The head file (audit.head: {seq, hash} of the last entry, rewritten after each append) is what catches a removed
// tail: cutting the newest lines off leaves a chain that is valid on its own, but shorter than the head says.
// Alternatives were weighed: a signature or MAC needs a key the same attacker could read; fsync'ing the head too
// would double the cost of an entry. The head is overwritten in place with one fixed-size write (HEAD_BYTES at
// offset 0, padded with spaces): one sector, so all-or-nothing in practice, and ~15 us, where write + rename costs
// ~500 us on ext4 (it flushes the new file on a replacing rename); only its creation is fsync'ed. It is written
// after the entry is on disk, so it never runs ahead of the log; a crash (or a power loss, the overwrite not being
// fsync'ed) can leave it behind. When the entries past it chain on from it, the next start moves it on and records
// that in the chain (op audit.head_behind); until then verify reports them as possibly inserted. A head that still
// reads as damaged is ignored at start and reported by verify.
import fs from 'node:fs';
import path from 'node:path';
import { fsyncDir, mkdirDurable, writeAll } from '../auth/atomic-file.js';
import {
  GENESIS, HEAD_BEHIND_OP, HEAD_BYTES, HEAD_FILE, LOG_FILE, TORN_WRITE_OP, entryHash, isChained, parseHead,
} from './chain.js';

/**
 * @typedef {{time?: string, user: string|null, role: string|null, ip: string|null, op: string, target?: string,
 *   outcome: 'ok'|'denied'|'failed', detail?: string}} AuditEntry
 * @typedef {AuditEntry & {seq?: number}} StoredAuditEntry  what query() returns: entries written before the chain
 *   have no seq; prev and hash are left out
 */

export class AuditLog {
  /** @param {{dir: string, maxBytes?: number, keep?: number}} o */
  constructor({ dir, maxBytes = 5 * 1024 * 1024, keep = 5 }) {
    mkdirDurable(dir);
    this.dir = dir;
    this.file = path.join(dir, LOG_FILE);
    this.headFile = path.join(dir, HEAD_FILE);
    this.maxBytes = maxBytes;
    this.keep = keep;
    this.size = fs.existsSync(this.file) ? fs.statSync(this.file).size : 0;
    const cut = this.repairTornTail();
    const head = this.readHead();
    const disk = this.lastOnDisk();
    const { seq, hash } = resume(head, disk);
    /** seq of the last entry written (0: none yet) */
    this.seq = seq;
    /** its hash, the `prev` of the next entry */
    this.lastHash = hash;
    const behind = head && disk && head.seq < disk.seq && this.continuesFrom(head) ? disk.seq - head.seq : 0;
    /** @type {AuditEntry[]} what this start repaired (also in the chain), for the BFF to say so */
    this.repairs = [];
    /** @type {Omit<AuditEntry, 'op'|'detail'>} */
    const self = { user: null, role: null, ip: null, outcome: 'failed' };
    if (cut) {
      this.repairs.push({ ...self, op: TORN_WRITE_OP, target: LOG_FILE,
        detail: `cut ${cut} bytes: the incomplete last line of ${LOG_FILE} (a write interrupted by a crash or power loss)` });
    }
    if (behind) {
      this.repairs.push({ ...self, op: HEAD_BEHIND_OP, target: HEAD_FILE,
        detail: `the head said seq ${head.seq}, the log ran on to seq ${disk.seq} (a crash or power loss before the head was updated); moved on` });
    }
    for (const r of this.repairs) this.record(r);
  }

  /**
   * Where the chain goes on: the last chained entry on disk (the current file, or the newest rotated one holding
   * chained entries), unless the head is at or past it: then the head, so a tail removed (or the last entry
   * rewritten) while the BFF was stopped stays visible as a gap instead of being papered over by the next entry.
   * A log with only entries from before the chain (or none) starts a new chain at seq 1.
   * @returns {{seq: number, hash: string}}
   */
  resumePoint() {
    return resume(this.readHead(), this.lastOnDisk());
  }

  /** @returns {{seq: number, hash: string} | null} */
  readHead() {
    try { return parseHead(fs.readFileSync(this.headFile, 'utf8')); } catch { return null; /* no head yet */ }
  }

  /** The files, newest first. */
  files() {
    return [this.file, ...Array.from({ length: this.keep }, (_, i) => `${this.file}.${i + 1}`)];
  }

  /** The last chained entry on disk (see resumePoint). */
  lastOnDisk() {
    for (const f of this.files()) {
      const e = lastChainedEntry(f);
      if (e) return e;
    }
    return null;
  }

  /**
   * A last line without its newline was being written when the BFF stopped. Unless it is complete JSON (only its
   * newline missing: that is ended and left to verify), it is cut off; fsync'ed before anything is appended.
   * @returns {number} the bytes cut (0: none)
   */
  repairTornTail() {
    if (this.size === 0) return 0;
    const fd = fs.openSync(this.file, 'r+');
    try {
      const start = lastNewline(fd, this.size) + 1;
      if (start === this.size) return 0;
      const fragment = Buffer.alloc(this.size - start);
      fs.readSync(fd, fragment, 0, fragment.length, start);
      let complete = true;
      try { JSON.parse(fragment.toString('utf8')); } catch { complete = false; }
      if (complete) {
        fs.writeSync(fd, '\n', this.size);
      } else {
        fs.ftruncateSync(fd, start);
      }
      fs.fsyncSync(fd);
      const cut = complete ? 0 : this.size - start;
      this.size = complete ? this.size + 1 : start;
      return cut;
    } finally {
      fs.closeSync(fd);
    }
  }

  /**
   * Do the entries after the head's continue the chain from it (the head's entry is there with its hash, and each
   * one after it follows)? Lines other than chained entries in between mean no: that is for verify to report.
   * @param {{seq: number, hash: string}} head
   */
  continuesFrom(head) {
    /** @type {import('./chain.js').ChainedEntry[]} newest first */
    const tail = [];
    for (const f of this.files()) {
      let text;
      try { text = fs.readFileSync(f, 'utf8'); } catch { continue; }
      const lines = text.split('\n');
      for (let i = lines.length - 1; i >= 0; i--) {
        if (lines[i] === '') continue;
        let e;
        try { e = JSON.parse(lines[i]); } catch { return false; }
        if (!isChained(e)) return false;
        tail.push(e);
        if (e.seq <= head.seq) {
          if (e.seq !== head.seq || e.hash !== head.hash) return false;
          for (let k = tail.length - 1; k > 0; k--) {
            const a = tail[k];
            const b = tail[k - 1];
            if (b.seq !== a.seq + 1 || b.prev !== a.hash || entryHash(b) !== b.hash) return false;
          }
          return true;
        }
      }
    }
    return false;
  }

  /** @param {AuditEntry} entry */
  record(entry) {
    /** @type {Record<string, unknown>} */
    const e = { seq: this.seq + 1, time: new Date().toISOString(), ...entry };
    e.seq = this.seq + 1;
    e.prev = this.lastHash;
    delete e.hash;
    e.hash = entryHash(e);
    const line = JSON.stringify(e) + '\n';
    const bytes = Buffer.byteLength(line);
    if (this.size + bytes > this.maxBytes && this.size > 0) this.rotate();
    // Synchronous on purpose: an audit entry is on disk before the command's answer goes out.
    this.append(Buffer.from(line, 'utf8'));
    this.size += bytes;
    this.seq = /** @type {number} */ (e.seq);
    this.lastHash = /** @type {string} */ (e.hash);
    this.writeHead();
  }

  /**
   * Appends and fdatasyncs (which covers the new size). A failed write is cut back off, so that the next entry does
   * not follow a torn line.
   * @param {Buffer} buf
   */
  append(buf) {
    const fd = fs.openSync(this.file, 'a', 0o600);
    let before = 0;
    try {
      before = fs.fstatSync(fd).size;
      writeAll(fd, buf);
      fs.fdatasyncSync(fd);
    } catch (e) {
      try { fs.ftruncateSync(fd, before); } catch { /* the start repairs it */ }
      throw e;
    } finally {
      fs.closeSync(fd);
    }
    // A new file (the first entry, or the first after a rotation): its name must be on disk too.
    if (before === 0) fsyncDir(this.dir);
  }

  /**
   * Overwrites the head with the last seq and hash: one write of HEAD_BYTES at offset 0 (see the top). Not
   * fsync'ed, but when it is created (a power loss would otherwise leave an empty head).
   */
  writeHead() {
    const text = JSON.stringify({ seq: this.seq, hash: this.lastHash }).padEnd(HEAD_BYTES - 1) + '\n';
    const { O_WRONLY, O_CREAT, O_EXCL } = fs.constants;
    let created = true;
    let fd;
    try {
      fd = fs.openSync(this.headFile, O_WRONLY | O_CREAT | O_EXCL, 0o600);
    } catch (e) {
      if (e.code !== 'EEXIST') throw e;
      created = false;
      fd = fs.openSync(this.headFile, O_WRONLY);
    }
    try {
      fs.writeSync(fd, text, 0);
      // A longer file (damaged, or edited by hand) would leave bytes after ours.
      if (fs.fstatSync(fd).size > HEAD_BYTES) fs.ftruncateSync(fd, HEAD_BYTES);
      if (created) fs.fsyncSync(fd);
    } finally {
      fs.closeSync(fd);
    }
    if (created) fsyncDir(this.dir);
  }

  /** Renames only; the next append's directory fsync makes them durable with the new file. */
  rotate() {
    for (let i = this.keep - 1; i >= 1; i--) {
      const from = `${this.file}.${i}`;
      if (fs.existsSync(from)) fs.renameSync(from, `${this.file}.${i + 1}`);
    }
    fs.renameSync(this.file, `${this.file}.1`);
    fs.rmSync(`${this.file}.${this.keep + 1}`, { force: true });
    this.size = 0;
  }

  /**
   * Newest first, across rotated files. Entries keep their seq (when they have one); the chain fields are left out.
   * @param {{user?: string, op?: string, outcome?: string, since?: string, offset?: number, limit?: number}} q
   * @returns {{total: number, offset: number, limit: number, entries: StoredAuditEntry[]}}
   */
  query({ user, op, outcome, since, offset = 0, limit = 50 } = {}) {
    const all = [];
    for (const f of this.files()) {
      let text;
      try { text = fs.readFileSync(f, 'utf8'); } catch { continue; }
      const lines = text.split('\n').filter(Boolean).reverse();
      for (const l of lines) {
        let e;
        try { e = JSON.parse(l); } catch { continue; }
        if (!e || typeof e !== 'object') continue;
        if (user && e.user !== user) continue;
        if (op && e.op !== op) continue;
        if (outcome && e.outcome !== outcome) continue;
        if (since && e.time < since) continue;
        const { prev: _p, hash: _h, ...shown } = e;
        all.push(shown);
      }
    }
    return { total: all.length, offset, limit, entries: all.slice(offset, offset + limit) };
  }
}

/**
 * Where the chain goes on (see resumePoint).
 * @param {{seq: number, hash: string} | null} head @param {{seq: number, hash: string} | null} disk
 */
function resume(head, disk) {
  if (head && (!disk || head.seq >= disk.seq)) return head;
  if (disk) return { seq: disk.seq, hash: disk.hash };
  return { seq: 0, hash: GENESIS };
}

/** Offset of the last newline before `size`, read backwards in chunks; -1 when there is none. @param {number} fd @param {number} size */
function lastNewline(fd, size) {
  const CHUNK = 64 * 1024;
  const buf = Buffer.alloc(CHUNK);
  for (let end = size; end > 0;) {
    const n = Math.min(CHUNK, end);
    fs.readSync(fd, buf, 0, n, end - n);
    const i = buf.subarray(0, n).lastIndexOf(0x0a);
    if (i >= 0) return end - n + i;
    end -= n;
  }
  return -1;
}

/**
 * The last line of a file that is a chained entry, read backwards in chunks (only the tail is read when it ends
 * with one). Lines that are not JSON (a torn write) or carry no chain fields are skipped.
 * @param {string} file @returns {import('./chain.js').ChainedEntry | null}
 */
function lastChainedEntry(file) {
  let fd;
  try { fd = fs.openSync(file, 'r'); } catch { return null; }
  try {
    const CHUNK = 64 * 1024;
    let pos = fs.fstatSync(fd).size;
    let rest = Buffer.alloc(0); // bytes after pos not yet split into lines (the start of the earliest line seen)
    while (pos > 0) {
      const n = Math.min(CHUNK, pos);
      pos -= n;
      const chunk = Buffer.alloc(n);
      fs.readSync(fd, chunk, 0, n, pos);
      const buf = Buffer.concat([chunk, rest]);
      // Complete lines are those after a newline in buf (or all of buf once the start of the file is reached).
      let end = buf.length;
      for (let i = buf.length - 1; i >= -1; i--) {
        if (i >= 0 && buf[i] !== 0x0a) continue;
        if (i < 0 && pos > 0) break;
        const e = parseLine(buf.subarray(i + 1, end));
        if (e) return e;
        end = i;
      }
      rest = buf.subarray(0, Math.max(end, 0));
    }
    return null;
  } finally {
    fs.closeSync(fd);
  }
}

/** @param {Buffer} bytes */
function parseLine(bytes) {
  if (bytes.length === 0) return null;
  try {
    const e = JSON.parse(bytes.toString('utf8'));
    return isChained(e) ? e : null;
  } catch {
    return null;
  }
}
