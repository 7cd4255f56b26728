// @vitest-environment node
import { describe, it, expect, vi } from 'vitest';
import { request, api } from '../../src/lib/core/api.js';

/** @param {number} status @param {any} [body] */
const respond = (status, body) =>
  vi.fn(async (/** @type {any} */ _url, /** @type {any} */ _init) => new Response(body === undefined ? null : JSON.stringify(body), { status }));

describe('api client', () => {
  it('returns ok with parsed JSON and sends JSON with the cookie', async () => {
    const f = respond(200, { username: 'ann', role: 'admin' });
    const r = await request('POST', '/api/auth/login', { username: 'ann', password: 'pw' }, f);
    expect(r).toEqual({ kind: 'ok', status: 200, data: { username: 'ann', role: 'admin' } });
    const [url, init] = f.mock.calls[0];
    expect(url).toBe('/api/auth/login');
    expect(init.credentials).toBe('same-origin');
    expect(init.headers['Content-Type']).toBe('application/json');
    expect(JSON.parse(init.body)).toEqual({ username: 'ann', password: 'pw' });
  });

  it('maps 401 to unauthorized (logged out) with the server message', async () => {
    const r = await request('GET', '/api/auth/me', undefined, respond(401, { error: 'not logged in' }));
    expect(r).toMatchObject({ kind: 'unauthorized', status: 401, error: 'not logged in' });
  });

  it('maps a network error to offline, not to logged out', async () => {
    const f = vi.fn(async () => {
      throw new TypeError('Failed to fetch');
    });
    const r = await request('GET', '/api/config', undefined, f);
    expect(r.kind).toBe('offline');
  });

  it('maps 403 to forbidden and 429 to an error with its status', async () => {
    expect((await request('GET', '/api/system', undefined, respond(403, { error: 'admin only' }))).kind).toBe('forbidden');
    const r = await request('POST', '/api/auth/login', {}, respond(429, { error: 'slow down' }));
    expect(r).toMatchObject({ kind: 'error', status: 429, error: 'slow down' });
  });

  it('keeps the body of a refusal (a 409 from the control lease names the holder)', async () => {
    const body = { error: 'control is held by ann (operator)', holder: { username: 'ann', role: 'operator' } };
    const r = await request('POST', '/api/control/take', undefined, respond(409, body));
    expect(r).toEqual({ kind: 'error', status: 409, error: body.error, data: body });
  });

  it('accepts 204 without a body', async () => {
    const r = await request('POST', '/api/auth/logout', undefined, respond(204));
    expect(r).toEqual({ kind: 'ok', status: 204, data: null });
  });

  it('control lease calls: take sends force only for a take-over', async () => {
    const f = respond(200, { holder: null, you: false });
    vi.stubGlobal('fetch', f);
    await api.control();
    await api.controlTake();
    await api.controlTake({ force: true });
    await api.controlHeartbeat();
    await api.controlRelease();
    expect(f.mock.calls.map(([u, i]) => [i.method, u, i.body ?? null])).toEqual([
      ['GET', '/api/control', null],
      ['POST', '/api/control/take', null],
      ['POST', '/api/control/take', '{"force":true}'],
      ['POST', '/api/control/heartbeat', null],
      ['POST', '/api/control/release', null],
    ]);
    vi.unstubAllGlobals();
  });

  it('a request that is not answered within its timeout is offline, saying so; without a timeout it waits', async () => {
    /** @type {AbortSignal | undefined} */
    let seen;
    const hang = vi.fn((/** @type {any} */ _url, /** @type {RequestInit} */ init) => new Promise((_, reject) => {
      seen = init.signal ?? undefined;
      init.signal?.addEventListener('abort', () => reject(init.signal?.reason));
    }));
    const r = await request('POST', '/api/control/heartbeat', undefined, /** @type {any} */ (hang), 30);
    expect(r).toEqual({ kind: 'offline', error: 'no answer within 0.03 s' });
    expect(seen?.aborted).toBe(true);
    await request('GET', '/api/config', undefined, respond(200, {}));
    const f = respond(200, {});
    await request('GET', '/api/config', undefined, f);
    expect(f.mock.calls[0][1].signal).toBeUndefined();
  });

  it('the heartbeat passes its timeout on', async () => {
    const f = respond(200, { holder: null, you: false });
    vi.stubGlobal('fetch', f);
    await api.controlHeartbeat(1000);
    expect(f.mock.calls[0][1].signal).toBeInstanceOf(AbortSignal);
    vi.unstubAllGlobals();
  });
});
