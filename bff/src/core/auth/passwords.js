// scrypt password hashes ("scrypt$N$r$p$salt$hash", base64). node:crypto runs scrypt off the main thread.
import crypto from 'node:crypto';
import { promisify } from 'node:util';

const scrypt = /** @type {(pw: string, salt: Buffer, len: number, opts: object) => Promise<Buffer>} */ (promisify(crypto.scrypt));
const PARAMS = { N: 16384, r: 8, p: 1 };
const KEYLEN = 32;

/** @param {string} password @returns {Promise<string>} */
export async function hashPassword(password) {
  const salt = crypto.randomBytes(16);
  const key = await scrypt(password, salt, KEYLEN, { ...PARAMS, maxmem: 64 * 1024 * 1024 });
  return ['scrypt', PARAMS.N, PARAMS.r, PARAMS.p, salt.toString('base64'), key.toString('base64')].join('$');
}

/** @param {string} password @param {string} stored @returns {Promise<boolean>} */
export async function verifyPassword(password, stored) {
  const parts = String(stored).split('$');
  if (parts.length !== 6 || parts[0] !== 'scrypt') return false;
  const [N, r, p] = parts.slice(1, 4).map(Number);
  const salt = Buffer.from(parts[4], 'base64');
  const expected = Buffer.from(parts[5], 'base64');
  const key = await scrypt(password, salt, expected.length, { N, r, p, maxmem: 64 * 1024 * 1024 });
  return crypto.timingSafeEqual(key, expected);
}

// A fixed hash to verify against when the user does not exist, so timing does not reveal it.
export const DUMMY_HASH = 'scrypt$16384$8$1$AAAAAAAAAAAAAAAAAAAAAA==$' + Buffer.alloc(32).toString('base64');

/** @param {number} [bytes] */
export function randomPassword(bytes = 12) {
  return crypto.randomBytes(bytes).toString('base64url');
}
