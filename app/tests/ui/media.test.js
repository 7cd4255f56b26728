import { describe, it, expect, vi, afterEach } from 'vitest';
import { watchMedia } from '../../src/lib/ui/media.js';

afterEach(() => vi.unstubAllGlobals());

describe('watchMedia', () => {
  it('reports the match now and on every change, and stops on cleanup', () => {
    /** @type {(() => void) | null} */
    let listener = null;
    const mq = { matches: true, addEventListener: (/** @type {string} */ _e, /** @type {() => void} */ f) => (listener = f), removeEventListener: () => (listener = null) };
    vi.stubGlobal('matchMedia', () => mq);
    /** @type {boolean[]} */
    const seen = [];
    const stop = watchMedia('(min-width: 768px)', (m) => seen.push(m));
    mq.matches = false;
    /** @type {any} */ (listener)();
    stop();
    expect(seen).toEqual([true, false]);
    expect(listener).toBeNull();
  });
  it('matches nothing without matchMedia', () => {
    vi.stubGlobal('matchMedia', undefined);
    /** @type {boolean[]} */
    const seen = [];
    watchMedia('(min-width: 768px)', (m) => seen.push(m))();
    expect(seen).toEqual([false]);
  });
});
