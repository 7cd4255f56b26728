// @vitest-environment node
import { describe, it, expect } from 'vitest';
import { ageMs, isStale, formatAge, freshness } from '../../src/lib/ui/staleness.js';

describe('staleness', () => {
  it('ages and stale marks', () => {
    expect(ageMs(1000, 4000)).toBe(3000);
    expect(ageMs(null, 4000)).toBeNull();
    expect(ageMs(5000, 4000)).toBe(0); // clock skew never gives a negative age
    expect(isStale(1000, 2000, 2500)).toBe(false);
    expect(isStale(1000, 2000, 3001)).toBe(true);
    expect(isStale(null, 2000, 0)).toBe(true);
  });

  it('formats ages for people', () => {
    expect([0, 1500, 12_000, 59_999, 60_000, 3_599_000, 3_600_000, 47 * 3_600_000, 49 * 3_600_000].map(formatAge)).toEqual([
      'just now', 'just now', '12 s ago', '59 s ago', '1 min ago', '59 min ago', '1 h ago', '47 h ago', '2 d ago',
    ]);
    expect(formatAge(null)).toBe('never');
  });

  it('says live, updated, stale or no data', () => {
    expect(freshness({ at: null, periodMs: 1000, now: 0, live: true })).toEqual({ stale: false, text: 'live' });
    expect(freshness({ at: 0, periodMs: 5000, now: 3000 })).toEqual({ stale: false, text: 'updated 3 s ago' });
    expect(freshness({ at: 0, periodMs: 5000, now: 7000 })).toEqual({ stale: true, text: 'stale · 7 s ago' });
    // An event-driven value whose link is down is stale whatever its age.
    expect(freshness({ at: 0, periodMs: 60_000, now: 3000, live: false })).toEqual({ stale: true, text: 'stale · 3 s ago' });
    expect(freshness({ at: null, periodMs: 5000, now: 0 })).toEqual({ stale: true, text: 'no data' });
  });
});
