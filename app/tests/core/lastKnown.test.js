// @vitest-environment node
import { describe, it, expect } from 'vitest';
import { IDBFactory } from 'fake-indexeddb';
import { LastKnownStore } from '../../src/lib/core/lastKnown.js';

const store = (o = {}) => new LastKnownStore({ idb: new IDBFactory(), now: () => 1234, ...o });

describe('LastKnownStore (IndexedDB)', () => {
  it('keeps the last state per page id, with when it was saved', async () => {
    const s = store();
    expect(await s.load('home')).toBeNull();
    expect(await s.save('home', { mode: { mode: 'idle', at: 1 } }, { user: 'ann' })).toBe(true);
    await s.save('system', { users: [{ username: 'ann' }] }, { user: 'ann', savedAt: 99 });
    expect(await s.load('home')).toEqual({ id: 'home', data: { mode: { mode: 'idle', at: 1 } }, savedAt: 1234, user: 'ann' });
    expect((await s.load('system'))?.savedAt).toBe(99);
    await s.save('home', { mode: { mode: 'running', at: 2 } }, { user: 'ann' });
    expect((await s.load('home'))?.data.mode.mode).toBe('running');
  });

  it('survives a new store on the same database (a reload)', async () => {
    const idb = new IDBFactory();
    await new LastKnownStore({ idb }).save('home', { x: 1 });
    expect((await new LastKnownStore({ idb }).load('home'))?.data).toEqual({ x: 1 });
  });

  it("does not hand one user's state to another; clear() forgets everything (logout)", async () => {
    const s = store();
    await s.save('system', { users: ['secret'] }, { user: 'admin' });
    expect(await s.load('system', { user: 'operator' })).toBeNull();
    expect(await s.load('system', { user: 'admin' })).not.toBeNull();
    await s.remove('system');
    expect(await s.load('system')).toBeNull();
    await s.save('a', 1);
    await s.save('b', 2);
    await s.clear();
    expect(await s.load('a')).toBeNull();
    expect(await s.load('b')).toBeNull();
  });

  it('without IndexedDB it is an empty store that never throws', async () => {
    const s = new LastKnownStore({ idb: null });
    expect(await s.save('home', { x: 1 })).toBe(false);
    expect(await s.load('home')).toBeNull();
    await s.clear();
  });

  it('data that cannot be cloned is not stored, and does not throw', async () => {
    const s = store();
    expect(await s.save('home', { fn: () => 1 })).toBe(false);
    expect(await s.load('home')).toBeNull();
  });
});
