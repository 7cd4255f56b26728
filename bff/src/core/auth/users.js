// The users file: {version: 1, users: [{username, role, hash}]}. Hashes only; re-read when it changes on disk,
// so users added with the CLI while the BFF runs can log in without a restart. Every change is written with
// writeFileAtomic: once add/passwd/remove has returned, the change survives a crash or a power loss.
import fs from 'node:fs';
import path from 'node:path';
import { removeStaleTemps, writeFileAtomic } from './atomic-file.js';
import { hashPassword, verifyPassword, DUMMY_HASH, randomPassword } from './passwords.js';

/** @typedef {{username: string, role: string, hash: string, locale?: string}} UserRecord */

/** The app's languages (app/project.inlang/settings.json; a test keeps the two lists equal). */
export const LOCALES = ['en', 'es', 'fi', 'de'];

export const USERNAME_RE = /^[a-z][a-z0-9_.-]{1,31}$/;

export class UsersError extends Error {}

export class UserStore {
  /** @param {string} file */
  constructor(file) {
    this.file = file;
    /** @type {UserRecord[]} */
    this.users = [];
    this.mtimeMs = -1;
    // Temp files of writes a crash interrupted (never read; only their disk space).
    removeStaleTemps(path.dirname(file), path.basename(file));
  }

  exists() {
    return fs.existsSync(this.file);
  }

  /** Re-read the file if it changed. A missing file is an empty user list. */
  refresh() {
    let st;
    try {
      st = fs.statSync(this.file);
    } catch (e) {
      if (e.code === 'ENOENT') { this.users = []; this.mtimeMs = -1; return; }
      throw e;
    }
    if (st.mtimeMs === this.mtimeMs && st.size === this.size) return;
    const doc = JSON.parse(fs.readFileSync(this.file, 'utf8'));
    if (!doc || !Array.isArray(doc.users)) throw new UsersError(`${this.file}: not a users file`);
    this.users = doc.users.filter((u) => u && typeof u.username === 'string' && typeof u.hash === 'string');
    this.mtimeMs = st.mtimeMs;
    this.size = st.size;
  }

  save() {
    writeFileAtomic(this.file, JSON.stringify({ version: 1, users: this.users }, null, 2) + '\n', 0o600);
    this.mtimeMs = -1;
  }

  /** @returns {{username: string, role: string}[]} */
  list() {
    this.refresh();
    return this.users.map(({ username, role }) => ({ username, role }));
  }

  /** @param {string} username */
  get(username) {
    this.refresh();
    return this.users.find((u) => u.username === username) || null;
  }

  /** @param {string} username @param {string} role @param {string} password */
  async add(username, role, password) {
    if (!USERNAME_RE.test(username)) throw new UsersError(`invalid user name "${username}" (a-z, 0-9, _ . -, 2-32 chars, starting with a letter)`);
    checkPassword(password);
    this.refresh();
    if (this.users.some((u) => u.username === username)) throw new UsersError(`user "${username}" already exists`);
    this.users.push({ username, role, hash: await hashPassword(password) });
    this.save();
  }

  /** @param {string} username @param {string} password */
  async passwd(username, password) {
    checkPassword(password);
    this.refresh();
    const u = this.users.find((x) => x.username === username);
    if (!u) throw new UsersError(`no user "${username}"`);
    u.hash = await hashPassword(password);
    this.save();
  }

  /** @param {string} username */
  remove(username) {
    this.refresh();
    const n = this.users.length;
    this.users = this.users.filter((u) => u.username !== username);
    if (this.users.length === n) throw new UsersError(`no user "${username}"`);
    this.save();
  }

  /**
   * @param {string} username @param {string} password
   * @returns {Promise<{username: string, role: string, locale?: string} | null>}
   */
  async authenticate(username, password) {
    const u = typeof username === 'string' ? this.get(username) : null;
    // Verify against a dummy hash for unknown users so both paths take the same time.
    const ok = await verifyPassword(String(password ?? ''), u ? u.hash : DUMMY_HASH);
    return u && ok ? publicUser(u) : null;
  }

  /**
   * The user as the app sees it (no hash).
   * @param {string} username @returns {{username: string, role: string, locale?: string} | null}
   */
  profile(username) {
    const u = this.get(username);
    return u ? publicUser(u) : null;
  }

  /**
   * Keep the user's language with the account (null: follow the browser). Written before it returns.
   * @param {string} username @param {string | null} locale
   */
  setLocale(username, locale) {
    if (locale !== null && !LOCALES.includes(locale)) throw new UsersError(`unknown language "${locale}" (one of ${LOCALES.join(', ')})`);
    this.refresh();
    const u = this.users.find((x) => x.username === username);
    if (!u) throw new UsersError(`no user "${username}"`);
    if (locale === null) delete u.locale;
    else u.locale = locale;
    this.save();
    return publicUser(u);
  }
}

/** @param {UserRecord} u */
const publicUser = (u) => ({ username: u.username, role: u.role, ...(u.locale && LOCALES.includes(u.locale) ? { locale: u.locale } : {}) });

/** @param {string} password */
function checkPassword(password) {
  if (typeof password !== 'string' || password.length < 8) throw new UsersError('password must have at least 8 characters');
}

/**
 * First start without a users file: one user per role of the cell file, named after the role, with a random
 * password, written once to a 0600 file in DATA_DIR.
 * @param {UserStore} store @param {string} dataDir @param {string[]} roles
 * @returns {Promise<null | {file: string, users: {username: string, role: string, password: string}[]}>}
 */
export async function ensureInitialUsers(store, dataDir, roles) {
  if (store.exists()) return null;
  const created = roles.map((role) => ({ username: role, role, password: randomPassword() }));
  for (const u of created) {
    if (!USERNAME_RE.test(u.username)) throw new UsersError(`invalid user name "${u.username}" (a-z, 0-9, _ . -, 2-32 chars, starting with a letter)`);
  }
  const users = await Promise.all(created.map(async (u) => ({ username: u.username, role: u.role, hash: await hashPassword(u.password) })));
  // The passwords before the users, each file in one write: a crash in between leaves no users file, so the next
  // start begins again; the other order (or one user at a time) would leave users whose passwords nobody has.
  const file = `${dataDir}/initial-passwords.txt`;
  writeFileAtomic(file, created.map((u) => `${u.username} (${u.role}): ${u.password}`).join('\n') + '\n', 0o600);
  store.users = users;
  store.save();
  return { file, users: created };
}
