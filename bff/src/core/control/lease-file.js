// The control lease on disk, so that a restarted BFF can give it back to its holder (ControlLease.resume).
// Written on every heartbeat: temp file and rename, so a crash leaves the old or the new content, never a torn
// one. No fsync: a saved lease is only worth anything for the heartbeat timeout (seconds), and after a power
// loss it is stale anyway.
import fs from 'node:fs';
import path from 'node:path';

/** @typedef {import('./lease.js').SavedLease} SavedLease */

export class LeaseFile {
  /** @param {string} file @param {(m: string) => void} [log] */
  constructor(file, log = () => {}) {
    this.file = file;
    this.tmp = path.join(path.dirname(file), `.${path.basename(file)}.tmp`);
    this.log = log;
  }

  /** The saved holder, or null (none, or a file that is not one: logged, and ignored). @returns {SavedLease | null} */
  read() {
    let text;
    try {
      text = fs.readFileSync(this.file, 'utf8');
    } catch (e) {
      if (/** @type {NodeJS.ErrnoException} */ (e).code !== 'ENOENT') this.log(`control lease: cannot read ${this.file}: ${e}`);
      return null;
    }
    try {
      const v = JSON.parse(text);
      if (v === null) return null;
      const ok = v && typeof v === 'object' && ['username', 'role', 'sid'].every((k) => typeof v[k] === 'string')
        && Number.isFinite(v.since) && Number.isFinite(v.beat);
      if (ok) return { username: v.username, role: v.role, sid: v.sid, since: v.since, beat: v.beat };
    } catch { /* reported below */ }
    this.log(`control lease: ${this.file} is not a saved lease; starting with no holder`);
    return null;
  }

  /** @param {SavedLease | null} saved */
  write(saved) {
    try {
      fs.writeFileSync(this.tmp, JSON.stringify(saved), { mode: 0o600 });
      fs.renameSync(this.tmp, this.file);
    } catch (e) {
      // A lease that cannot be saved still works; it just does not survive a restart.
      this.log(`control lease: cannot save ${this.file}: ${e}`);
    }
  }
}
