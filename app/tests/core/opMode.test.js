// @vitest-environment node
import { describe, it, expect } from 'vitest';
import { OpMode, modeTone } from '../../src/lib/core/opMode.svelte.js';
import { RosConnection } from '../../src/lib/core/connection.svelte.js';
import { makeFakeFactory, makeFakeTimers, flush } from '../fakeRos.js';

describe('OpMode', () => {
  it('follows the configured topic on the shared connection', async () => {
    const { factory, rosList, topics } = makeFakeFactory();
    const t = makeFakeTimers();
    const conn = new RosConnection({ factory, url: () => 'ws://x/ros', setTimer: t.setTimer, clearTimer: t.clearTimer });
    const m = new OpMode();
    const stop = m.follow(conn, { topic: '/cell/mode', type: 'cell_msgs/OperationMode' });
    conn.start();
    await flush();
    rosList[0].emit('connection');
    await flush();
    expect(topics[0]).toMatchObject({ name: '/cell/mode', type: 'cell_msgs/OperationMode' });
    topics[0].deliver({ mode: 'paused', source: 'ui', stamp: { secs: 1, nsecs: 0 } });
    expect(m.mode).toBe('paused');
    expect(m.source).toBe('ui');
    stop();
    expect(conn.subscriptionCount).toBe(0);
  });

  it('maps modes to badge tones', () => {
    expect(modeTone('running')).toBe('ok');
    expect(modeTone('alarm')).toBe('danger');
    expect(modeTone('something-new')).toBe('neutral');
    expect(modeTone(null)).toBe('neutral');
  });
});

describe('OpMode last known value', () => {
  it('keeps the last mode and the moment the link dropped; the live value clears', () => {
    let t = 100;
    const m = new OpMode(() => t);
    m.reset(); // nothing known yet
    expect(m.last).toBeNull();
    m.update({ mode: 'running', source: 'ui' });
    expect(m.last).toEqual({ mode: 'running', source: 'ui', at: 100 });
    t = 5000;
    m.reset();
    expect(m.mode).toBeNull();
    expect(m.last).toEqual({ mode: 'running', source: 'ui', at: 5000 });
    t = 9000;
    m.reset(); // still down: the moment it was last known stays
    expect(m.last?.at).toBe(5000);
  });
});
