// Append-only JSON-lines audit log in DATA_DIR, rotated by size (audit.log, audit.log.1, ... audit.log.N).
import fs from 'node:fs';
import path from 'node:path';

/**
 * @typedef {{time?: string, user: string|null, role: string|null, ip: string|null, op: string, target?: string,
 *   outcome: 'ok'|'denied'|'failed', detail?: string}} AuditEntry
 */

export class AuditLog {
  /** @param {{dir: string, maxBytes?: number, keep?: number}} o */
  constructor({ dir, maxBytes = 5 * 1024 * 1024, keep = 5 }) {
    fs.mkdirSync(dir, { recursive: true });
    this.file = path.join(dir, 'audit.log');
    this.maxBytes = maxBytes;
    this.keep = keep;
    this.size = fs.existsSync(this.file) ? fs.statSync(this.file).size : 0;
  }

  /** @param {AuditEntry} entry */
  record(entry) {
    const line = JSON.stringify({ time: new Date().toISOString(), ...entry }) + '\n';
    if (this.size + line.length > this.maxBytes && this.size > 0) this.rotate();
    // Synchronous on purpose: an audit entry is written before the command's answer goes out.
    fs.appendFileSync(this.file, line, { mode: 0o600 });
    this.size += Buffer.byteLength(line);
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
   * Newest first, across rotated files.
   * @param {{user?: string, op?: string, outcome?: string, since?: string, offset?: number, limit?: number}} q
   * @returns {{total: number, offset: number, limit: number, entries: AuditEntry[]}}
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
        if (user && e.user !== user) continue;
        if (op && e.op !== op) continue;
        if (outcome && e.outcome !== outcome) continue;
        if (since && e.time < since) continue;
        all.push(e);
      }
    }
    return { total: all.length, offset, limit, entries: all.slice(offset, offset + limit) };
  }
}
