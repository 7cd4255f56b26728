// The audit log's hash chain, shared by the writer (audit-log.js) and the verifier (verify.js).
//
// Every chained entry carries `seq` (1, 2, 3, ... monotonic across rotations), `prev` (the `hash` of the entry
// before it; GENESIS for the first entry of a chain) and
//   hash = sha256(prev + canonical JSON of the entry without `hash`)
// so `prev` is both an explicit field and part of what is hashed. The explicit field lets the verifier tell
// *which* link broke: an entry whose own hash is right but that does not chain to its predecessor was inserted,
// or its predecessor was rewritten; an entry whose hash does not match its content was altered.
// Canonical JSON: JSON.stringify with the keys of every object sorted (the same rules for undefined, Date, ...).
import crypto from 'node:crypto';

export const GENESIS = '0'.repeat(64);
export const HEAD_FILE = 'audit.head';
/** The head file's fixed size: its JSON padded with spaces, and a newline (see audit-log.js). */
export const HEAD_BYTES = 128;
export const LOG_FILE = 'audit.log';
/** Ops of the entries the BFF writes at start when it repaired the log after a crash or power loss (audit-log.js). */
export const TORN_WRITE_OP = 'audit.torn_write';
export const HEAD_BEHIND_OP = 'audit.head_behind';

/**
 * @typedef {{seq: number, prev: string, hash: string, [k: string]: unknown}} ChainedEntry
 */

/** @param {unknown} value @returns {string} */
export function canonicalJson(value) {
  return JSON.stringify(value, (_k, v) => (v && typeof v === 'object' && !Array.isArray(v)
    ? Object.fromEntries(Object.keys(v).sort().map((k) => [k, v[k]]))
    : v));
}

/**
 * The hash an entry must carry: over everything but its `hash` field (which may be present or not).
 * @param {Record<string, unknown>} entry
 */
export function entryHash(entry) {
  const { hash: _ignored, ...rest } = entry;
  return crypto.createHash('sha256').update(String(entry.prev ?? '')).update(canonicalJson(rest)).digest('hex');
}

/**
 * A chained entry has a numeric seq and string prev and hash; entries written before the chain have none of them.
 * @param {unknown} e @returns {e is ChainedEntry}
 */
export function isChained(e) {
  return !!e && typeof e === 'object' && Number.isSafeInteger(/** @type {any} */ (e).seq)
    && typeof /** @type {any} */ (e).prev === 'string' && typeof /** @type {any} */ (e).hash === 'string';
}

/**
 * An entry written before this chain existed (or by a forger who left the fields out): a JSON object with none of
 * seq, prev, hash.
 * @param {unknown} e
 */
export function isLegacy(e) {
  return !!e && typeof e === 'object' && !Array.isArray(e) && !('seq' in e) && !('prev' in e) && !('hash' in e);
}

/**
 * The head file: the last seq and hash written, so a removed tail is seen (see audit-log.js).
 * @param {string} text @returns {{seq: number, hash: string} | null} null when it is not a valid head
 */
export function parseHead(text) {
  try {
    const h = JSON.parse(text);
    return h && Number.isSafeInteger(h.seq) && typeof h.hash === 'string' && /^[0-9a-f]{64}$/.test(h.hash) ? { seq: h.seq, hash: h.hash } : null;
  } catch {
    return null;
  }
}
