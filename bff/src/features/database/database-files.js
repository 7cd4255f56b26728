// Replacing the cell's database files (cell file section `database`) from a USB drive or an uploaded file,
// with a timestamped backup of the old file and restore from backups. No shell commands; every path is
// built from the configured directory and validated single names, and drive paths are checked by realpath.
//
// Drive rule (listDrives): for each USB root (e.g. /media, /run/media), each directory D directly under it
//   1. is a drive if D is a mount point (its device differs from the root's);
//   2. otherwise, if directories directly under D are mount points, those are drives (D is a per-user folder,
//      /media/<user>/<drive> as udisks2 mounts them) and D itself is not;
//   3. otherwise (nothing mounted: test/demo directories, bind mounts on the same device), D is a per-user
//      folder when it holds only directories, and then each non-empty one of them is a drive; else D is a
//      drive when it is not empty.
// Hidden entries (".name") and symbolic links directly under a root or user folder are ignored.
//
// Power loss: a replace or restore is answered only once the new file, its backup and both directory entries are
// fsync'ed; each goes through a hidden temp file renamed into place, so a file or backup is never seen torn. Temp
// files a crash left behind are removed at the next start.
import fs from 'node:fs';
import fsp from 'node:fs/promises';
import path from 'node:path';
import { removeStaleTemps, tempName } from '../../core/auth/atomic-file.js';
import { checkContent, ContentError } from './content-check.js';

export const DEFAULT_USB_ROOTS = ['/media', '/run/media'];
export const DEFAULT_MAX_UPLOAD_BYTES = 10 * 1024 * 1024;

/**
 * An error with an HTTP status and a message meant for the user; a client error's `code` and `params` are the same
 * for the app to say in the user's language (`database.not_listed` {file}: app/messages/errors).
 */
export class DatabaseError extends Error {
  /** @param {number} status @param {string} message @param {string} [code] @param {Record<string, string | number>} [params] */
  constructor(status, message, code = undefined, params = undefined) {
    super(message);
    this.status = status;
    this.code = code;
    this.params = params;
  }
}

/**
 * USB roots: USB_ROOTS (colon-separated) wins over the cell file, which wins over the defaults.
 * @param {string|undefined} envValue process.env.USB_ROOTS @param {{database?: {usb_roots?: string[]}}} [cell]
 */
export function resolveUsbRoots(envValue, cell) {
  const fromEnv = (envValue || '').split(':').filter(Boolean).map((p) => path.resolve(p));
  if (fromEnv.length) return fromEnv;
  return cell?.database?.usb_roots?.length ? cell.database.usb_roots : DEFAULT_USB_ROOTS;
}

// The names and paths the API takes, as JSON Schema string rules: the checks below and the OpenAPI document
// (routes.js) both use these, so the document states exactly what the code enforces.
// (No lookaheads in the patterns: every JSON Schema tool and test generator understands them.)
const NOT_SEP = '[^/\\\\\\u0000]'; // any character but '/', '\' and NUL
/** A segment or name that is not '', '.' or '..'. */
const SEGMENT = `(?:[^./\\\\\\u0000]|\\.[^./\\\\\\u0000]|\\.\\.${NOT_SEP})${NOT_SEP}*`;

/** A database file (cell file `database.files`, the same pattern as the cell schema's fileName). */
export const FILE_NAME = Object.freeze({ type: 'string', minLength: 1, maxLength: 255, pattern: '^[A-Za-z0-9][A-Za-z0-9_.-]*$' });
/** A drive id as listDrives makes them: "<root index>:<dir>[:<dir>]"; no '/', '\', NUL, '..'; at most 255 UTF-8 bytes. */
export const DRIVE_ID = Object.freeze({ type: 'string', minLength: 3, maxLength: 255, pattern: `^[0-9]+:(?:\\.?[^./\\\\\\u0000])+\\.?$` });
/** A backup as #backup names them: "<file>.<ISO time>[-n]" (ASCII letters, digits, '_', '.', ':', '-'). */
export const BACKUP_NAME = Object.freeze({ type: 'string', minLength: 3, maxLength: 255, pattern: '^[A-Za-z0-9][A-Za-z0-9_.:-]*$' });
/** A path relative to a drive root: segments separated by '/', none empty, '.' or '..', no '\' or NUL; trailing '/' allowed. */
export const REL_PATH = Object.freeze({ type: 'string', minLength: 1, maxLength: 4096, pattern: `^${SEGMENT}(?:/${SEGMENT})*/*$` });
/** REL_PATH or '' (the drive root). */
export const REL_PATH_OR_ROOT = Object.freeze({ type: 'string', maxLength: 4096, pattern: `^(?:${SEGMENT}(?:/${SEGMENT})*/*)?$` });

/** @type {WeakMap<object, RegExp>} */
const compiled = new WeakMap();
/**
 * Does s satisfy a string rule above (lengths in code points, as JSON Schema counts them)?
 * @param {{minLength?: number, maxLength?: number, pattern: string}} rule @param {unknown} s
 */
export function satisfies(rule, s) {
  if (typeof s !== 'string') return false;
  const n = [...s].length;
  if (n < (rule.minLength ?? 0) || n > (rule.maxLength ?? Infinity)) return false;
  let re = compiled.get(rule);
  if (!re) compiled.set(rule, (re = new RegExp(rule.pattern, 'u')));
  return re.test(s);
}

/**
 * A single file or drive name: no '/', '\', NUL, no '..', not '.', not empty, at most 255 bytes.
 * @param {unknown} s
 */
export function isSafeName(s) {
  return typeof s === 'string' && s.length > 0 && Buffer.byteLength(s) <= 255 && s !== '.' &&
    !s.includes('..') && !/[/\\\0]/.test(s);
}

/**
 * A relative path inside a drive (REL_PATH): segments separated by '/', none empty, '.', '..', with NUL or '\'.
 * @param {unknown} p @param {boolean} allowEmpty
 */
export function isSafeRelPath(p, allowEmpty = false) {
  return satisfies(allowEmpty ? REL_PATH_OR_ROOT : REL_PATH, p);
}

/** @param {string} root @param {string} p `p` is `root` or below it (both real paths). */
const inside = (root, p) => p === root || p.startsWith(root.endsWith(path.sep) ? root : root + path.sep);
const ext = (name) => path.extname(name).toLowerCase();

/**
 * @typedef {{username?: string|null, role?: string|null, ip?: string|null}} Actor
 * @typedef {{name: string, size: number|null, mtime: string|null, exists: boolean}} TargetInfo
 * @typedef {{id: string, label: string, path: string}} Drive
 */

export class DatabaseFiles {
  /**
   * @param {{cell: {database?: {directory: string, files: string[], usb_roots?: string[], max_upload_bytes?: number}},
   *   dataDir: string, usbRoots?: string[]|null, audit?: {record: (e: object) => void}|null,
   *   fsp?: typeof import('node:fs/promises'), keepBackups?: number, now?: () => Date}} o
   *   fsp: the file operations used for writing (tests inject failures); keepBackups: per file, oldest pruned.
   */
  constructor({ cell, dataDir, usbRoots, audit = null, fsp: fileOps = fsp, keepBackups = 20, now = () => new Date() }) {
    const db = cell.database || { directory: 'database', files: [] };
    this.cell = cell;
    this.dataDir = dataDir;
    this.dir = path.resolve(dataDir, db.directory);
    this.backupDir = path.join(this.dir, '.backups');
    this.targets = [...(db.files || [])];
    this.maxBytes = db.max_upload_bytes || DEFAULT_MAX_UPLOAD_BYTES;
    this.usbRoots = (usbRoots?.length ? usbRoots : db.usb_roots?.length ? db.usb_roots : DEFAULT_USB_ROOTS).map((r) => path.resolve(r));
    this.audit = audit;
    this.fs = fileOps;
    this.keepBackups = keepBackups;
    this.now = now;
    /** @type {Map<string, Promise<unknown>>} one replace/restore at a time per target */
    this.locks = new Map();
    for (const t of this.targets) for (const d of [this.dir, this.backupDir]) removeStaleTemps(d, t);
  }

  /** @returns {Promise<TargetInfo[]>} */
  async listTargets() {
    return Promise.all(this.targets.map(async (name) => {
      try {
        const st = await fsp.stat(path.join(this.dir, name));
        return { name, size: st.size, mtime: st.mtime.toISOString(), exists: true };
      } catch {
        return { name, size: null, mtime: null, exists: false };
      }
    }));
  }

  /** Drives currently present (see the rule at the top of this file). @returns {Promise<Drive[]>} */
  async listDrives() {
    /** @type {Drive[]} */
    const drives = [];
    for (const [ri, root] of this.usbRoots.entries()) {
      const rootSt = await statOrNull(root);
      if (!rootSt?.isDirectory()) continue;
      for (const d of await subdirs(root)) {
        const dPath = path.join(root, d.name);
        const add = (segments) => drives.push({ id: `${ri}:${segments.join(':')}`, label: segments.at(-1), path: path.join(root, ...segments) });
        if (d.st.dev !== rootSt.dev) { add([d.name]); continue; }
        const children = await subdirs(dPath);
        const mounted = children.filter((c) => c.st.dev !== d.st.dev);
        if (mounted.length) { for (const c of mounted) add([d.name, c.name]); continue; }
        const entries = await readdirOrEmpty(dPath);
        if (entries.length === 0) continue;
        if (entries.every((e) => e.isDirectory())) {
          for (const c of children) if ((await readdirOrEmpty(path.join(dPath, c.name))).length) add([d.name, c.name]);
        } else {
          add([d.name]);
        }
      }
    }
    return drives;
  }

  /**
   * Directories and files at `subpath` of a drive. Symbolic links are listed only when they resolve inside the drive.
   * @param {string} driveId @param {string} [subpath]
   * @returns {Promise<{drive: string, path: string, entries: {name: string, type: 'dir'|'file', size?: number, mtime?: string, targets?: string[]}[]}>}
   */
  async listDriveFiles(driveId, subpath = '') {
    const drive = await this.#drive(driveId);
    if (!isSafeRelPath(subpath, true)) throw new DatabaseError(400, 'invalid path', 'database.invalid_path');
    const dir = await this.#realInside(drive.real, subpath);
    const st = await fsp.stat(dir);
    if (!st.isDirectory()) throw new DatabaseError(400, 'not a directory', 'database.not_a_directory');
    /** @type {{name: string, type: 'file'|'dir', size?: number, mtime?: string, targets?: string[]}[]} */
    const entries = [];
    for (const e of await readdirOrEmpty(dir)) {
      if (e.name.startsWith('.')) continue;
      let full = path.join(dir, e.name);
      if (e.isSymbolicLink()) {
        try { full = await fsp.realpath(full); } catch { continue; }
        if (!inside(drive.real, full)) continue;
      }
      const s = await statOrNull(full);
      if (s?.isDirectory()) entries.push({ name: e.name, type: 'dir' });
      else if (s?.isFile()) {
        entries.push({ name: e.name, type: 'file', size: s.size, mtime: s.mtime.toISOString(), targets: this.targets.filter((t) => ext(t) === ext(e.name)) });
      }
    }
    entries.sort((a, b) => (a.type === b.type ? a.name.localeCompare(b.name) : a.type === 'dir' ? -1 : 1));
    return { drive: driveId, path: subpath.replace(/\/+$/, ''), entries };
  }

  /**
   * @param {string} target @param {string} driveId @param {string} relPath @param {Actor} user
   * @returns {Promise<{file: TargetInfo, backup: string|null}>}
   */
  async replaceFromDrive(target, driveId, relPath, user) {
    return this.#audited('database.replace', target, user, `from drive ${driveId}: ${relPath}`, async () => {
      this.#target(target);
      const drive = await this.#drive(driveId);
      if (!isSafeRelPath(relPath)) throw new DatabaseError(400, 'invalid path', 'database.invalid_path');
      const src = await this.#realInside(drive.real, relPath);
      const st = await fsp.stat(src);
      if (!st.isFile()) throw new DatabaseError(400, 'not a file', 'database.not_a_file');
      this.#sameExtension(target, relPath);
      if (st.size > this.maxBytes) throw tooLarge(this.maxBytes);
      return this.#install(target, () => fs.createReadStream(src), { check: true });
    });
  }

  /**
   * @param {string} target @param {string|import('node:stream').Readable} source a temporary file or a stream
   * @param {string} originalName the name the file had on the client (only its extension is used) @param {Actor} user
   */
  async replaceFromUpload(target, source, originalName, user) {
    return this.#audited('database.replace', target, user, `from upload ${JSON.stringify(String(originalName).slice(0, 200))}`, async () => {
      this.#target(target);
      this.#sameExtension(target, String(originalName || ''));
      if (typeof source === 'string' && (await fsp.stat(source)).size > this.maxBytes) throw tooLarge(this.maxBytes);
      return this.#install(target, () => (typeof source === 'string' ? fs.createReadStream(source) : source), { check: true });
    });
  }

  /** Backups of a target, newest first. @param {string} target */
  async listBackups(target) {
    this.#target(target);
    const out = [];
    for (const e of await readdirOrEmpty(this.backupDir)) {
      if (!e.isFile() || !isBackupOf(target, e.name) || e.name.endsWith('.tmp')) continue;
      const st = await statOrNull(path.join(this.backupDir, e.name));
      if (st) out.push({ name: e.name, size: st.size, mtime: st.mtime.toISOString() });
    }
    return out.sort((a, b) => (a.name < b.name ? 1 : a.name > b.name ? -1 : 0));
  }

  /** Put a backup back; the current file is backed up first, so a restore can be undone. @param {string} target @param {string} backupName @param {Actor} user */
  async restoreBackup(target, backupName, user) {
    return this.#audited('database.restore', target, user, `backup ${backupName}`, async () => {
      this.#target(target);
      if (!isBackupOf(target, backupName)) {
        throw new DatabaseError(400, `invalid backup name: expected ${target}.<time> as listed by GET .../backups`, 'database.invalid_backup', { file: target });
      }
      const src = path.join(this.backupDir, backupName);
      const st = await fsp.lstat(src).catch(() => null);
      if (!st?.isFile()) throw new DatabaseError(404, `no backup ${backupName}`, 'database.no_backup', { backup: backupName });
      // No content check: a backup was the live file once, and restoring must work even if checks got stricter.
      return this.#install(target, () => fs.createReadStream(src), { check: false });
    });
  }

  // --- internals ---

  #target(name) {
    if (this.targets.includes(name)) return; // the cell file's names are checked by its schema
    if (!satisfies(FILE_NAME, name) || !isSafeName(name)) throw new DatabaseError(400, 'invalid file name', 'database.invalid_name');
    throw new DatabaseError(404, `${name} is not a database file of this cell`, 'database.not_listed', { file: name });
  }

  #sameExtension(target, sourceName) {
    if (ext(sourceName) !== ext(target)) {
      // expected, got: '' for no extension.
      throw new DatabaseError(415, `${target} needs a ${ext(target) || 'extension-less'} file, not ${ext(sourceName) || 'one without extension'}`,
        'database.bad_extension', { file: target, expected: ext(target), got: ext(sourceName) });
    }
  }

  /** @returns {Promise<Drive & {real: string}>} */
  async #drive(id) {
    if (!satisfies(DRIVE_ID, id) || !isSafeName(id)) throw new DatabaseError(400, 'invalid drive id', 'database.invalid_drive');
    const noDrive = () => new DatabaseError(404, `no drive ${id}`, 'database.no_drive', { drive: id });
    const d = (await this.listDrives()).find((x) => x.id === id);
    if (!d) throw noDrive();
    try {
      return { ...d, real: await fsp.realpath(d.path) };
    } catch {
      throw noDrive();
    }
  }

  /** Real path of rel below root; 404 when missing, 403 when it resolves outside root (symbolic links). */
  async #realInside(root, rel) {
    let real;
    try {
      real = await fsp.realpath(path.join(root, rel));
    } catch (e) {
      // Names too long for the file system and symbolic-link loops cannot name a file there either.
      const shown = rel.slice(0, 300);
      if (['ENOENT', 'ENOTDIR', 'ENAMETOOLONG', 'ELOOP'].includes(e.code)) throw new DatabaseError(404, `no such file on the drive: ${shown}`, 'database.no_such_path', { path: shown });
      if (e.code === 'EACCES' || e.code === 'EPERM') throw new DatabaseError(403, `not readable on the drive: ${shown}`, 'database.not_readable', { path: shown });
      throw e;
    }
    if (!inside(root, real)) throw new DatabaseError(403, 'the path leads outside the drive', 'database.outside_drive');
    return real;
  }

  /** Run op; audit ok/denied/failed; I/O errors become a 500 DatabaseError. */
  async #audited(op, target, user, detail, fn) {
    const entry = { user: user?.username ?? null, role: user?.role ?? null, ip: user?.ip ?? null, op, target: String(target) };
    try {
      const result = await fn();
      this.audit?.record({ ...entry, outcome: 'ok', detail: result.backup ? `${detail}; old file kept as ${result.backup}` : detail });
      return result;
    } catch (e) {
      const err = e instanceof DatabaseError ? e : new DatabaseError(500, `could not write ${target}: ${e.code || e.message}`);
      this.audit?.record({ ...entry, outcome: err.status >= 500 ? 'failed' : 'denied', detail: `${detail}: ${err.message}` });
      throw err;
    }
  }

  /**
   * Copy into a temp file next to the target (size-limited, fsync), check it, back up the old file,
   * then rename over the target. Any failure removes the temp file and leaves the old file as it was.
   * @param {string} target @param {() => NodeJS.ReadableStream} open @param {{check: boolean}} o
   */
  async #install(target, open, { check }) {
    const prev = this.locks.get(target) || Promise.resolve();
    const run = prev.catch(() => {}).then(() => this.#installNow(target, open, check));
    this.locks.set(target, run);
    try {
      return await run;
    } finally {
      if (this.locks.get(target) === run) this.locks.delete(target);
    }
  }

  async #installNow(target, open, check) {
    const f = this.fs;
    const dest = path.join(this.dir, target);
    await mkdirDurable(f, this.dir);
    const old = await statOrNull(dest);
    const tmp = tempName(dest);
    let backup = null;
    let done = false;
    try {
      const fh = await f.open(tmp, 'wx', old ? old.mode & 0o777 : 0o644);
      let size = 0;
      try {
        for await (const chunk of open()) {
          size += chunk.length;
          if (size > this.maxBytes) throw tooLarge(this.maxBytes);
          await fh.write(chunk);
        }
        await fh.sync();
      } finally {
        await fh.close();
      }
      if (check) {
        try {
          checkContent(ext(target), await f.readFile(tmp));
        } catch (e) {
          if (e instanceof ContentError) throw new DatabaseError(422, `${target} not replaced: ${e.message}`, e.code, { file: target, ...e.params });
          throw e;
        }
      }
      if (old) backup = await this.#backup(dest, target);
      await f.rename(tmp, dest);
      done = true;
      await fsyncDir(this.dir);
    } finally {
      if (!done) {
        await f.rm(tmp, { force: true }).catch(() => {});
        if (backup) await f.rm(path.join(this.backupDir, backup), { force: true }).catch(() => {});
      }
    }
    await this.#prune(target).catch(() => {});
    const st = await fsp.stat(dest);
    return { file: { name: target, size: st.size, mtime: st.mtime.toISOString(), exists: true }, backup };
  }

  /**
   * Copy the current file to .backups/<name>.<ISO time> through a temp file (fsync, rename, directory fsync), so
   * a backup is complete or absent, never torn; returns the backup's name.
   */
  async #backup(dest, target) {
    const f = this.fs;
    await mkdirDurable(f, this.backupDir, 0o700);
    const tmp = tempName(path.join(this.backupDir, target));
    let renamed = false;
    try {
      await f.copyFile(dest, tmp, fs.constants.COPYFILE_EXCL);
      const fh = await f.open(tmp, 'r');
      try { await fh.sync(); } finally { await fh.close(); }
      const stamp = this.now().toISOString();
      // Replacements of one target run one at a time (#install), so nothing takes the name between check and rename.
      for (let i = 0; ; i++) {
        const name = `${target}.${stamp}${i ? `-${i}` : ''}`;
        if (await fsp.lstat(path.join(this.backupDir, name)).then(() => true, () => false)) {
          if (i < 100) continue;
          throw Object.assign(new Error(`backup ${name} exists`), { code: 'EEXIST' });
        }
        await f.rename(tmp, path.join(this.backupDir, name));
        renamed = true;
        await fsyncDir(this.backupDir);
        return name;
      }
    } finally {
      if (!renamed) await f.rm(tmp, { force: true }).catch(() => {});
    }
  }

  async #prune(target) {
    const all = await this.listBackups(target);
    for (const b of all.slice(this.keepBackups)) await this.fs.rm(path.join(this.backupDir, b.name), { force: true });
  }
}

/** A backup name of that target: "<target>.<suffix>" (BACKUP_NAME), the suffix a single safe name. */
const isBackupOf = (target, name) => satisfies(BACKUP_NAME, name) && name.startsWith(`${target}.`) && isSafeName(name.slice(target.length + 1));

/** @param {number} max */
export const tooLarge = (max) => new DatabaseError(413, `the file is larger than the limit of ${max} bytes`, 'database.too_large', { limit: max });

async function statOrNull(p) {
  try { return await fsp.stat(p); } catch { return null; }
}

async function readdirOrEmpty(dir) {
  try { return await fsp.readdir(dir, { withFileTypes: true }); } catch { return []; }
}

/** Real directories (not symbolic links, not hidden) directly in dir, with their stat. */
async function subdirs(dir) {
  const out = [];
  for (const e of await readdirOrEmpty(dir)) {
    if (!e.isDirectory() || e.name.startsWith('.')) continue;
    const st = await statOrNull(path.join(dir, e.name));
    if (st) out.push({ name: e.name, st });
  }
  return out;
}

/**
 * mkdir -p whose new directories survive a power loss: the parent of each one created is fsync'ed.
 * @param {typeof import('node:fs/promises')} f @param {string} dir @param {number} [mode]
 */
async function mkdirDurable(f, dir, mode) {
  const first = await f.mkdir(dir, { recursive: true, ...(mode === undefined ? {} : { mode }) });
  if (!first) return;
  for (let d = path.resolve(dir); ; d = path.dirname(d)) {
    await fsyncDir(path.dirname(d));
    if (d === path.resolve(first)) break;
  }
}

async function fsyncDir(dir) {
  try {
    const fh = await fsp.open(dir, 'r');
    try { await fh.sync(); } finally { await fh.close(); }
  } catch { /* best effort on some filesystems */ }
}
