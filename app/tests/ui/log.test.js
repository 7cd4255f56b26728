import { describe, it, expect } from 'vitest';
import { logLines, levelOf, rosTimeMs, clockTime } from '../../src/lib/ui/log.js';

describe('log panel lines', () => {
  it('newest first, bounded, every level labelled', () => {
    const entries = Array.from({ length: 5 }, (_, i) => ({ stamp: { secs: 100 + i, nsecs: 0 }, level: ['info', 'warning', 'error', 'warn', 'x'][i], text: `t${i}` }));
    const lines = logLines({ entries }, 3);
    expect(lines.map((l) => l.text)).toEqual(['t4', 't3', 't2']);
    expect(lines.map((l) => l.label)).toEqual(['Info', 'Warning', 'Error']);
    expect(lines[0].at).toBe(104000);
    expect(logLines(null)).toEqual([]);
  });
  it('levels, times', () => {
    expect(levelOf('FATAL')).toBe('error');
    expect(rosTimeMs({ sec: 1, nanosec: 5e8 })).toBe(1500);
    expect(rosTimeMs({})).toBeNull();
    expect(clockTime(null)).toBe('--:--:--');
  });
});
