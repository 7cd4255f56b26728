// @vitest-environment node
import { describe, it, expect } from 'vitest';
import { modeView, notLiveBecause, isKnownMode } from '../../../src/lib/features/home/logic.js';

describe('home: modeView', () => {
  const last = { mode: 'running', source: 'ui', at: 5000 };
  const saved = { mode: 'paused', source: 'e2e', at: 1000 };

  it('the live mode wins and is fresh', () => {
    expect(modeView({ live: 'manual', liveSource: 'pendant', last, saved })).toEqual({ mode: 'manual', source: 'pendant', live: true, at: null, from: 'live' });
  });

  it('without a live mode: the newest known one, not live, with when it last held', () => {
    expect(modeView({ live: null, last, saved })).toMatchObject({ mode: 'running', live: false, at: 5000, from: 'memory' });
    expect(modeView({ live: null, last: null, saved })).toMatchObject({ mode: 'paused', at: 1000, from: 'saved' });
    expect(modeView({ live: null, last: { ...last, at: 10 }, saved })).toMatchObject({ mode: 'paused', from: 'saved' });
    expect(modeView({ live: null, last: null, saved: null })).toEqual({ mode: null, source: null, live: false, at: null, from: 'none' });
  });

  it('ignores malformed saved records', () => {
    expect(isKnownMode({ mode: '', at: 1 })).toBe(false);
    expect(isKnownMode({ mode: 'idle' })).toBe(false);
    expect(modeView({ live: null, last: null, saved: /** @type {any} */ ({ mode: 3 }) }).from).toBe('none');
  });
});

describe('home: notLiveBecause', () => {
  it('offline first, then a link that went down; not the first connect', () => {
    expect(notLiveBecause({ offline: true, conn: 'connected', downSince: null })).toBe('offline');
    expect(notLiveBecause({ offline: false, conn: 'disconnected', downSince: 1 })).toBe('disconnected');
    expect(notLiveBecause({ offline: false, conn: 'connecting', downSince: 1 })).toBe('disconnected');
    expect(notLiveBecause({ offline: false, conn: 'connecting', downSince: null })).toBeNull();
    expect(notLiveBecause({ offline: false, conn: 'connected', downSince: null })).toBeNull();
  });
});
