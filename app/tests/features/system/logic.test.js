// @vitest-environment node
import { describe, it, expect } from 'vitest';
import { healthRows, uptimeText, STALE_AFTER_MS, POLL_MS } from '../../../src/lib/features/system/logic.js';

describe('system logic', () => {
  it('health rows say up/down in words', () => {
    const h = { status: 'ok', ros: { rosbridge: true, master: false }, uptime_s: 5, version: '1' };
    expect(healthRows(h, false)).toEqual([
      { label: 'BFF', ok: true, text: 'ok' },
      { label: 'rosbridge', ok: true, text: 'up' },
      { label: 'ROS master', ok: false, text: 'down' },
    ]);
    expect(healthRows(h, true)[0]).toEqual({ label: 'BFF', ok: false, text: 'unreachable' });
    expect(healthRows(null, false)).toEqual([]);
  });

  it('the plant broker link, when the cell reports to one', () => {
    const link = (/** @type {string} */ state, error = '') => ({ state, since: 1, error });
    const plant = { broker: 'mqtt://b:1883', group_id: 'g', edge_node_id: 'n', view: link('off') };
    const h = { status: 'ok', ros: { rosbridge: true, master: true }, uptime_s: 5, version: '1' };
    expect(healthRows({ ...h, plant: { ...plant, reporting: link('connected') } }, false)[3]).toEqual({ label: 'Plant broker mqtt://b:1883', ok: true, text: 'connected' });
    expect(healthRows({ ...h, plant: { ...plant, reporting: link('down', 'connect ECONNREFUSED') } }, false)[3]).toEqual({ label: 'Plant broker mqtt://b:1883', ok: false, text: 'down: connect ECONNREFUSED' });
    expect(healthRows({ ...h, plant: { ...plant, reporting: link('off') } }, false)).toHaveLength(3);
  });

  it('uptime', () => {
    expect(uptimeText(65)).toBe('1 min 5 s');
    expect(uptimeText(3 * 3600 + 120)).toBe('3 h 2 min');
    expect(uptimeText(2 * 86400 + 3600)).toBe('2 d 1 h');
    expect(uptimeText(NaN)).toBe('—');
  });

  it('values are stale after two missed polls', () => {
    expect(STALE_AFTER_MS).toBeGreaterThan(2 * POLL_MS);
  });
});
