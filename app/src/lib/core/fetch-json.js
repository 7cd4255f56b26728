/**
 * One JSON request to the BFF (same origin, cookie session), answered as what came back: the status and the JSON
 * body, or why nothing came back. No DOM and no catalogue: the lease's heartbeat worker uses it too.
 */

/** @typedef {{ status: number, statusText: string, data: any } | { offline: string }} RawAnswer */

/**
 * @param {string} method
 * @param {string} path  e.g. '/api/config'
 * @param {any} [body]   serialised as JSON when given
 * @param {typeof fetch} [fetchImpl]
 * @param {number} [timeoutMs]  give up after this long (an answer that never comes is offline); default: never
 * @returns {Promise<RawAnswer>}
 */
export async function fetchJson(method, path, body, fetchImpl = globalThis.fetch, timeoutMs = 0) {
  /** @type {RequestInit} */
  const init = {
    method,
    credentials: 'same-origin',
    headers: { Accept: 'application/json' },
    cache: 'no-store',
  };
  if (body !== undefined) {
    init.headers = { ...init.headers, 'Content-Type': 'application/json' };
    init.body = JSON.stringify(body);
  }
  if (timeoutMs > 0) init.signal = AbortSignal.timeout(timeoutMs);
  let res;
  try {
    res = await fetchImpl(path, init);
  } catch (e) {
    // fetch only rejects on network failure (offline, server down, CORS) or our timeout: not an auth answer.
    if (e instanceof Error && e.name === 'TimeoutError') return { offline: `no answer within ${timeoutMs / 1000} s` };
    return { offline: e instanceof Error ? e.message : String(e) };
  }
  return { status: res.status, statusText: res.statusText, data: await readJson(res) };
}

/** @param {Response} res */
async function readJson(res) {
  if (res.status === 204) return null;
  try {
    const text = await res.text();
    return text ? JSON.parse(text) : null;
  } catch {
    return null;
  }
}
