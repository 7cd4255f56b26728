// Durable file writes: after a crash or a power loss, readers see the old or the new content, never a torn one,
// and once a write has returned it survives a power loss (temp file + fsync + rename + directory fsync).
import crypto from 'node:crypto';
import fs from 'node:fs';
import path from 'node:path';

/** @param {string} file @param {string|Buffer} data @param {number} [mode] */
export function writeFileAtomic(file, data, mode = 0o600) {
  const dir = path.dirname(file);
  mkdirDurable(dir);
  const tmp = tempName(file);
  const fd = fs.openSync(tmp, 'wx', mode);
  let renamed = false;
  try {
    try {
      writeAll(fd, Buffer.isBuffer(data) ? data : Buffer.from(data, 'utf8'));
      fs.fsyncSync(fd);
    } finally {
      fs.closeSync(fd);
    }
    fs.renameSync(tmp, file);
    renamed = true;
  } finally {
    if (!renamed) fs.rmSync(tmp, { force: true });
  }
  fsyncDir(dir);
}

/**
 * The temp file a write to `file` goes through: hidden, next to it (a rename only replaces atomically within one
 * file system), named after the writer's pid so that removeStaleTemps knows when it is left over from a crash.
 * @param {string} file
 */
export function tempName(file) {
  return path.join(path.dirname(file), `.${path.basename(file)}.${process.pid}.${crypto.randomBytes(6).toString('hex')}.tmp`);
}

/**
 * Removes the temp files of writes to `dir/name` that a crashed process left (see tempName): those of processes
 * that no longer run. Best effort; readers never look at them anyway.
 * @param {string} dir @param {string} name @returns {string[]} the files removed
 */
export function removeStaleTemps(dir, name) {
  const prefix = `.${name}.`;
  /** @type {string[]} */
  const removed = [];
  let entries;
  try { entries = fs.readdirSync(dir); } catch { return removed; }
  for (const e of entries) {
    if (!e.startsWith(prefix) || !e.endsWith('.tmp')) continue;
    const pid = Number(e.slice(prefix.length).split('.')[0]);
    if (!Number.isSafeInteger(pid) || pid <= 0 || pid === process.pid || alive(pid)) continue;
    try { fs.rmSync(path.join(dir, e), { force: true }); removed.push(e); } catch { /* best effort */ }
  }
  return removed;
}

/** @param {number} pid */
function alive(pid) {
  try { process.kill(pid, 0); return true; } catch (e) { return e.code === 'EPERM'; }
}

/** Writes all of buf (a write may be partial) at the fd's position. @param {number} fd @param {Buffer} buf */
export function writeAll(fd, buf) {
  for (let off = 0; off < buf.length;) off += fs.writeSync(fd, buf, off, buf.length - off);
}

/**
 * mkdir -p that survives a power loss: the parent of each directory it creates is fsync'ed, or the new
 * directory (and all written into it) could vanish with its entry.
 * @param {string} dir
 */
export function mkdirDurable(dir) {
  const first = fs.mkdirSync(dir, { recursive: true });
  if (first) for (let d = path.resolve(dir); ; d = path.dirname(d)) { fsyncDir(path.dirname(d)); if (d === path.resolve(first)) break; }
}

/** Makes the directory's entries (a create, rename or delete in it) durable. @param {string} dir */
export function fsyncDir(dir) {
  let fd;
  try { fd = fs.openSync(dir, 'r'); } catch { return; }
  try { fs.fsyncSync(fd); } catch { /* directory fsync is best effort on some filesystems */ } finally { fs.closeSync(fd); }
}
