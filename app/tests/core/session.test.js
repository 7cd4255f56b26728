// @vitest-environment node
import { describe, it, expect, vi } from 'vitest';
import { Session } from '../../src/lib/core/session.svelte.js';

const user = { username: 'ann', role: 'operator' };
const config = {
  cell: { id: 'c1', name: 'Demo cell' },
  role: 'operator',
  pages: [{ id: 'home', title: 'Home' }],
  operation_mode: { topic: '/cell/mode', type: 'cell_msgs/OperationMode', modes: ['idle'] },
};

/** @param {Record<string, any>} answers */
function fakeApi(answers) {
  return /** @type {any} */ ({
    me: vi.fn(async () => answers.me),
    config: vi.fn(async () => answers.config),
    login: vi.fn(async () => answers.login),
    logout: vi.fn(async () => ({ kind: 'ok', status: 204, data: null })),
  });
}

function memoryStorage() {
  const m = new Map();
  return /** @type {Storage} */ ({
    getItem: (k) => (m.has(k) ? m.get(k) : null),
    setItem: (k, v) => void m.set(k, String(v)),
    removeItem: (k) => void m.delete(k),
  });
}

describe('Session', () => {
  it('online: loads user and config and caches them', async () => {
    const storage = memoryStorage();
    const s = new Session({ api: fakeApi({ me: { kind: 'ok', data: user }, config: { kind: 'ok', data: config } }), storage });
    expect(await s.refresh()).toBe('authenticated');
    expect(s.user).toEqual(user);
    expect(s.config?.cell.name).toBe('Demo cell');
    expect(s.offline).toBe(false);

    // An offline reload (new Session, network error) still has the last identity to draw the shell.
    const s2 = new Session({ api: fakeApi({ me: { kind: 'offline', error: 'x' } }), storage });
    expect(await s2.refresh()).toBe('authenticated');
    expect(s2.offline).toBe(true);
    expect(s2.user).toEqual(user);
    expect(s2.config?.pages).toEqual(config.pages);
  });

  it('offline without a cache is logged out', async () => {
    const s = new Session({ api: fakeApi({ me: { kind: 'offline', error: 'x' } }), storage: memoryStorage() });
    expect(await s.refresh()).toBe('logged-out');
    expect(s.offline).toBe(true);
  });

  it('401 online clears the session and the cache', async () => {
    const storage = memoryStorage();
    const ok = new Session({ api: fakeApi({ me: { kind: 'ok', data: user }, config: { kind: 'ok', data: config } }), storage });
    await ok.refresh();
    const s = new Session({ api: fakeApi({ me: { kind: 'unauthorized', status: 401, error: 'no' } }), storage });
    expect(await s.refresh()).toBe('logged-out');
    expect(s.user).toBeNull();
    expect(storage.getItem('cell-ui.session.v1')).toBeNull();
  });

  it('login reports 401 and 429 as errors, success loads config', async () => {
    const bad = new Session({ api: fakeApi({ login: { kind: 'unauthorized', status: 401, error: 'invalid credentials' } }), storage: null });
    expect(await bad.login('a', 'b')).toEqual({ ok: false, error: 'invalid credentials' });
    const slow = new Session({ api: fakeApi({ login: { kind: 'error', status: 429, error: 'too many attempts' } }), storage: null });
    expect(await slow.login('a', 'b')).toEqual({ ok: false, error: 'too many attempts' });

    const api = fakeApi({ login: { kind: 'ok', data: user }, me: { kind: 'ok', data: user }, config: { kind: 'ok', data: config } });
    const s = new Session({ api, storage: null });
    expect(await s.login('ann', 'pw')).toEqual({ ok: true });
    expect(api.login).toHaveBeenCalledWith('ann', 'pw');
    expect(s.auth).toBe('authenticated');
    expect(s.config?.cell.id).toBe('c1');
  });

  it('a logout made offline is completed against the server on the next refresh', async () => {
    const storage = memoryStorage();
    const offlineApi = fakeApi({});
    offlineApi.logout = vi.fn(async () => ({ kind: 'offline', error: 'x' }));
    const s = new Session({ api: offlineApi, storage });
    s.user = user;
    await s.logout();
    expect(s.auth).toBe('logged-out');

    // Back online: the cookie is still valid (me would say 200), so logout must be sent first.
    const api = fakeApi({ me: { kind: 'unauthorized', status: 401, error: 'no' } });
    const s2 = new Session({ api, storage });
    expect(await s2.refresh()).toBe('logged-out');
    expect(api.logout).toHaveBeenCalledTimes(1);
    expect(api.logout.mock.invocationCallOrder[0]).toBeLessThan(api.me.mock.invocationCallOrder[0]);
    await s2.refresh();
    expect(api.logout).toHaveBeenCalledTimes(1);
  });
});
