// Append-only JSON-lines audit log in DATA_DIR, rotated by size (audit.log, audit.log.1, ... audit.log.N), and
// tamper-evident: every entry is chained to the one before it by a sha256 hash (see chain.js for the format), and
// the chain runs on across rotations (the first entry of a new file chains to the last one of the previous file).
// `npm run audit -- verify` checks it (verify.js).
//
// The head file (audit.head: {seq, hash} of the last entry, rewritten after each append) is what catches a removed
// tail: cutting the newest lines off leaves a chain that is valid on its own, but shorter than the head says.
// Alternatives were weighed: a signature or MAC needs a key the same attacker could read; fsync'ing or re-reading
// the log on each append costs far more. The head is overwritten in place with one fixed-size write (HEAD_BYTES at
// offset 0, padded with spaces): one sector, so all-or-nothing in practice, and ~15 us, where write + rename costs
// ~500 us on ext4 (it flushes the new file on a replacing rename). A head that still reads as damaged is ignored at
// start and reported by verify. The head is written after the entry, so a crash between the two leaves the log one
// entry ahead of the head, which verify reports (naming that possible cause) until the next entry updates the head.
import fs from 'node:fs';
import path from 'node:path';
import { GENESIS, HEAD_BYTES, HEAD_FILE, LOG_FILE, entryHash, isChained, parseHead } from './chain.js';

/**
 * @typedef {{time?: string, user: string|null, role: string|null, ip: string|null, op: string, target?: string,
 *   outcome: 'ok'|'denied'|'failed', detail?: string}} AuditEntry
 * @typedef {AuditEntry & {seq?: number}} StoredAuditEntry  what query() returns: entries written before the chain
 *   have no seq; prev and hash are left out
 */

export class AuditLog {
  /** @param {{dir: string, maxBytes?: number, keep?: number}} o */
  constructor({ dir, maxBytes = 5 * 1024 * 1024, keep = 5 }) {
    fs.mkdirSync(dir, { recursive: true });
    this.file = path.join(dir, LOG_FILE);
    this.headFile = path.join(dir, HEAD_FILE);
    this.maxBytes = maxBytes;
    this.keep = keep;
    this.size = fs.existsSync(this.file) ? fs.statSync(this.file).size : 0;
    // A torn last line (a crash mid-write) is ended with a newline so the next entry starts on a line of its own;
    // the fragment stays for verify to report.
    if (this.size > 0 && !endsWithNewline(this.file, this.size)) {
      fs.appendFileSync(this.file, '\n');
      this.size += 1;
    }
    const { seq, hash } = this.resumePoint();
    /** seq of the last entry written (0: none yet) */
    this.seq = seq;
    /** its hash, the `prev` of the next entry */
    this.lastHash = hash;
  }

  /**
   * Where the chain goes on: the last chained entry on disk (the current file, or the newest rotated one holding
   * chained entries), unless the head is at or past it: then the head, so a tail removed (or the last entry
   * rewritten) while the BFF was stopped stays visible as a gap instead of being papered over by the next entry.
   * A log with only entries from before the chain (or none) starts a new chain at seq 1.
   * @returns {{seq: number, hash: string}}
   */
  resumePoint() {
    let disk = null;
    for (const f of [this.file, ...Array.from({ length: this.keep }, (_, i) => `${this.file}.${i + 1}`)]) {
      disk = lastChainedEntry(f);
      if (disk) break;
    }
    let head = null;
    try { head = parseHead(fs.readFileSync(this.headFile, 'utf8')); } catch { /* no head yet */ }
    if (head && (!disk || head.seq >= disk.seq)) return head;
    if (disk) return { seq: disk.seq, hash: disk.hash };
    return { seq: 0, hash: GENESIS };
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
    // Synchronous on purpose: an audit entry is written before the command's answer goes out.
    fs.appendFileSync(this.file, line, { mode: 0o600 });
    this.size += bytes;
    this.seq = /** @type {number} */ (e.seq);
    this.lastHash = /** @type {string} */ (e.hash);
    this.writeHead();
  }

  /** Overwrites the head with the last seq and hash: one write of HEAD_BYTES at offset 0 (see the top). */
  writeHead() {
    const text = JSON.stringify({ seq: this.seq, hash: this.lastHash }).padEnd(HEAD_BYTES - 1) + '\n';
    const fd = fs.openSync(this.headFile, fs.constants.O_WRONLY | fs.constants.O_CREAT, 0o600);
    try {
      fs.writeSync(fd, text, 0);
      // A longer file (damaged, or edited by hand) would leave bytes after ours.
      if (fs.fstatSync(fd).size > HEAD_BYTES) fs.ftruncateSync(fd, HEAD_BYTES);
    } finally {
      fs.closeSync(fd);
    }
  }

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
    const files = [this.file, ...Array.from({ length: this.keep }, (_, i) => `${this.file}.${i + 1}`)];
    const all = [];
    for (const f of files) {
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

/** @param {string} file @param {number} size */
function endsWithNewline(file, size) {
  const fd = fs.openSync(file, 'r');
  try {
    const b = Buffer.alloc(1);
    fs.readSync(fd, b, 0, 1, size - 1);
    return b[0] === 0x0a;
  } finally {
    fs.closeSync(fd);
  }
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
