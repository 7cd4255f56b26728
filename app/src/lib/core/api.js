/**
 * Thin JSON client for the BFF (same origin, cookie session).
 * It never throws: every call resolves to an ApiResult so callers can tell
 * "logged out" (401) from "offline" (network error) without try/catch chains.
 * A refusal's `error` is in the user's language when the BFF gave its code (core/errors.js).
 */

import { fetchJson } from './fetch-json.js';

/**
 * @typedef {{ kind: 'ok', status: number, data: any }
 *   | { kind: 'unauthorized', status: 401, error: string, data?: any }
 *   | { kind: 'forbidden', status: 403, error: string, data?: any }
 *   | { kind: 'offline', error: string }
 *   | { kind: 'error', status: number, error: string, data?: any }} ApiResult
 * `data` on a refusal is the server's JSON body (e.g. a 409 from the control lease names the holder).
 */

/**
 * @param {string} method
 * @param {string} path  e.g. '/api/config'
 * @param {any} [body]   serialised as JSON when given
 * @param {typeof fetch} [fetchImpl]
 * @param {number} [timeoutMs]  give up after this long (an answer that never comes is 'offline'); default: never
 * @returns {Promise<ApiResult>}
 */
export async function request(method, path, body, fetchImpl = globalThis.fetch, timeoutMs = 0) {
  return resultOf(await fetchJson(method, path, body, fetchImpl, timeoutMs));
}

/**
 * What an answer means to the app (a refusal's text in the user's language).
 * @param {import('./fetch-json.js').RawAnswer} a
 * @returns {Promise<ApiResult>}
 */
export async function resultOf(a) {
  if ('offline' in a) return { kind: 'offline', error: a.offline };
  const { status, data } = a;
  if (status >= 200 && status < 300) return { kind: 'ok', status, data };
  const error = (await sayError(data)) || a.statusText || `HTTP ${status}`;
  if (status === 401) return { kind: 'unauthorized', status: 401, error, data };
  if (status === 403) return { kind: 'forbidden', status: 403, error, data };
  return { kind: 'error', status, error, data };
}

/**
 * An error body in the user's language. The catalogue of error texts is loaded with the first coded error, so the
 * login page does not carry it; without it (offline before it was cached) the BFF's English text.
 * @param {any} data
 */
async function sayError(data) {
  if (data && typeof data.code === 'string') {
    try {
      const { errorText } = await import('./errors.js');
      return errorText(data);
    } catch {
      /* not loadable: the English below */
    }
  }
  return data && typeof data.error === 'string' ? data.error : '';
}

export const api = {
  /** @param {string} username @param {string} password */
  login: (username, password) => request('POST', '/api/auth/login', { username, password }),
  logout: () => request('POST', '/api/auth/logout'),
  me: () => request('GET', '/api/auth/me'),
  /** @param {{ locale: string | null }} prefs */
  preferences: (prefs) => request('PUT', '/api/auth/me/preferences', prefs),
  config: () => request('GET', '/api/config'),
  health: () => request('GET', '/api/health'),
  system: () => request('GET', '/api/system'),
  // The control lease (one controlling session at a time; see core/lease.svelte.js).
  control: () => request('GET', '/api/control'),
  /** @param {{ force?: boolean }} [o] */
  controlTake: (o = {}) => request('POST', '/api/control/take', o.force ? { force: true } : undefined),
  /** @param {number} [timeoutMs] */
  controlHeartbeat: (timeoutMs) => request('POST', '/api/control/heartbeat', undefined, undefined, timeoutMs),
  controlRelease: () => request('POST', '/api/control/release'),
};
