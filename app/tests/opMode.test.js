import { describe, it, expect } from 'vitest';
import { OpMode, modeTone } from '../src/lib/ros/opMode.svelte.js';
import { RosConnection } from '../src/lib/ros/connection.svelte.js';
import { makeFakeFactory, makeFakeTimers, flush } from './fakeRos.js';

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
