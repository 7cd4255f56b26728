// Session tokens: short-lived HS256 JWTs signed with a key generated once into DATA_DIR (0600); the algorithm
// is pinned when verifying, so alg:none and algorithm-confusion tokens are refused. A login is a session id
// (sid) that lives on through renewed tokens while the app is in use; logout revokes the sid in a store that
// survives a restart, which kills every token of that login at once.
import crypto from 'node:crypto';
import fs from 'node:fs';
import path from 'node:path';
import jwt from 'jsonwebtoken';
import { writeFileAtomic } from './atomic-file.js';

const ALG = 'HS256';

/** @param {string} dataDir @returns {Buffer} */
export function loadOrCreateKey(dataDir) {
  const file = path.join(dataDir, 'session.key');
  try {
    const key = Buffer.from(fs.readFileSync(file, 'utf8').trim(), 'base64');
    if (key.length >= 32) return key;
  } catch (e) {
    if (e.code !== 'ENOENT') throw e;
  }
  const key = crypto.randomBytes(48);
  writeFileAtomic(file, key.toString('base64') + '\n', 0o600);
  return key;
}

/** Revoked session ids with the expiry of their last token; expired entries are pruned on write. */
export class RevocationList {
  /** @param {string} file */
  constructor(file) {
    this.file = file;
    /** @type {Map<string, number>} jti -> exp (s) */
    this.map = new Map();
    try {
      const doc = JSON.parse(fs.readFileSync(file, 'utf8'));
      for (const [k, v] of Object.entries(doc)) this.map.set(k, Number(v));
    } catch { /* none yet */ }
  }
  /** @param {string} sid @param {number} exp */
  revoke(sid, exp) {
    const now = Date.now() / 1000;
    for (const [k, v] of this.map) if (v < now) this.map.delete(k);
    this.map.set(sid, exp);
    writeFileAtomic(this.file, JSON.stringify(Object.fromEntries(this.map)), 0o600);
  }
  /** @param {string} sid */
  has(sid) {
    return this.map.has(sid);
  }
}

/** @typedef {{sub: string, role: string, sid: string, jti: string, exp: number, iat: number}} Claims */

export class TokenService {
  /** @param {{key: Buffer, ttlS: number, revoked: RevocationList}} o */
  constructor({ key, ttlS, revoked }) {
    this.key = key;
    this.ttlS = ttlS;
    this.revoked = revoked;
    /** @type {Map<string, number>} sid -> expiry (s) of its newest token, for sockets opened with an older one */
    this.newest = new Map();
  }
  /** @param {{username: string, role: string}} user @param {string} [sid] keep the session of a renewed token */
  issue(user, sid = crypto.randomUUID()) {
    const token = jwt.sign({ role: user.role, sid }, this.key, {
      algorithm: ALG, subject: user.username, expiresIn: this.ttlS, jwtid: crypto.randomUUID(),
    });
    const now = Math.floor(Date.now() / 1000);
    // One entry per live session: forget the ones whose newest token has expired.
    for (const [k, exp] of this.newest) if (exp <= now) this.newest.delete(k);
    this.newest.set(sid, now + this.ttlS);
    return token;
  }
  /** @param {string|undefined} token @returns {Claims|null} */
  verify(token) {
    if (!token) return null;
    try {
      const claims = /** @type {Claims} */ (jwt.verify(token, this.key, { algorithms: [ALG] }));
      if (!claims.jti || !claims.sid || this.revoked.has(claims.sid)) return null;
      return claims;
    } catch {
      return null;
    }
  }
  /** Renew when less than half the lifetime is left. @param {Claims} c */
  needsRenewal(c) {
    return c.exp - Date.now() / 1000 < this.ttlS / 2;
  }
  /** Still alive: not revoked and some token of the session not expired. @param {Claims} c */
  sessionAlive(c) {
    if (this.revoked.has(c.sid)) return false;
    return Math.max(c.exp, this.newest.get(c.sid) || 0) * 1000 > Date.now();
  }
  /** @param {Claims} claims */
  revoke(claims) {
    this.revoked.revoke(claims.sid, Math.max(claims.exp, this.newest.get(claims.sid) || 0));
    this.newest.delete(claims.sid);
  }
}
