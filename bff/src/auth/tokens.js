// Session tokens: HS256 JWTs signed with a key generated once into DATA_DIR (0600); the algorithm is pinned
// when verifying, so alg:none and algorithm-confusion tokens are refused. Logout revokes a token's jti in a
// store that survives a restart.
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

/** Revoked token ids with their expiry; expired entries are pruned on write. */
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
  /** @param {string} jti @param {number} exp */
  revoke(jti, exp) {
    const now = Date.now() / 1000;
    for (const [k, v] of this.map) if (v < now) this.map.delete(k);
    this.map.set(jti, exp);
    writeFileAtomic(this.file, JSON.stringify(Object.fromEntries(this.map)), 0o600);
  }
  /** @param {string} jti */
  has(jti) {
    return this.map.has(jti);
  }
}

/** @typedef {{sub: string, role: string, jti: string, exp: number, iat: number}} Claims */

export class TokenService {
  /** @param {{key: Buffer, ttlS: number, revoked: RevocationList}} o */
  constructor({ key, ttlS, revoked }) {
    this.key = key;
    this.ttlS = ttlS;
    this.revoked = revoked;
  }
  /** @param {{username: string, role: string}} user */
  issue(user) {
    return jwt.sign({ role: user.role }, this.key, {
      algorithm: ALG, subject: user.username, expiresIn: this.ttlS, jwtid: crypto.randomUUID(),
    });
  }
  /** @param {string|undefined} token @returns {Claims|null} */
  verify(token) {
    if (!token) return null;
    try {
      const claims = /** @type {Claims} */ (jwt.verify(token, this.key, { algorithms: [ALG] }));
      if (!claims.jti || this.revoked.has(claims.jti)) return null;
      return claims;
    } catch {
      return null;
    }
  }
  /** @param {Claims} claims */
  revoke(claims) {
    this.revoked.revoke(claims.jti, claims.exp);
  }
}
