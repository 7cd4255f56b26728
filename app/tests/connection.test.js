import { describe, it, expect } from 'vitest';
import { RosConnection, backoffDelay, defaultRosUrl } from '../src/lib/ros/connection.svelte.js';
import { makeFakeFactory, makeFakeTimers, flush } from './fakeRos.js';

function setup() {
  const f = makeFakeFactory();
  const timers = makeFakeTimers();
  const conn = new RosConnection({
    factory: f.factory,
    url: () => 'ws://test/ros',
    setTimer: timers.setTimer,
    clearTimer: timers.clearTimer,
  });
  return { ...f, timers, conn };
}

describe('backoffDelay', () => {
  it('doubles from 0.5 s and caps at 8 s', () => {
    expect([0, 1, 2, 3, 4, 5, 9].map((n) => backoffDelay(n))).toEqual([500, 1000, 2000, 4000, 8000, 8000, 8000]);
  });
});

describe('defaultRosUrl', () => {
  it('uses the page origin with /ros (ws on http)', () => {
    expect(defaultRosUrl()).toBe(`ws://${location.host}/ros`);
  });
});

describe('RosConnection', () => {
  it('goes connecting -> connected and connects to the given url', async () => {
    const { conn, rosList } = setup();
    expect(conn.state).toBe('disconnected');
    conn.start();
    expect(conn.state).toBe('connecting');
    await flush();
    expect(rosList).toHaveLength(1);
    expect(rosList[0].url).toBe('ws://test/ros');
    rosList[0].emit('connection');
    expect(conn.state).toBe('connected');
  });

  it('reconnects with exponential backoff, resets after success', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    const delays = [];
    for (let i = 0; i < 6; i++) {
      const r = rosList.at(-1);
      r.emit('error');
      r.emit('close'); // both fire for one failure: must schedule only one retry
      expect(conn.state).toBe('disconnected');
      expect(timers.pending).toHaveLength(1);
      delays.push(timers.runNext());
      await flush();
    }
    expect(delays).toEqual([500, 1000, 2000, 4000, 8000, 8000]);
    expect(rosList).toHaveLength(7);
    expect(rosList.slice(0, 6).every((r) => r.closed)).toBe(true);

    rosList.at(-1).emit('connection');
    expect(conn.state).toBe('connected');
    rosList.at(-1).emit('close');
    expect(timers.runNext()).toBe(500);
  });

  it('re-issues every live subscription after a reconnect, not the dropped ones', async () => {
    const { conn, rosList, topics, timers } = setup();
    const got = [];
    const unsubA = conn.subscribe('/cell/mode', 'cell_msgs/OperationMode', (m) => got.push(['a', m.mode]));
    conn.subscribe('/other', 'std_msgs/String', (m) => got.push(['b', m.data]), { throttle_rate: 100 });
    conn.start();
    await flush();
    rosList[0].emit('connection');
    await flush();
    expect(topics.map((t) => t.name)).toEqual(['/cell/mode', '/other']);
    expect(topics[1].options).toEqual({ throttle_rate: 100 });
    topics[0].deliver({ mode: 'running' });

    unsubA();
    expect(topics[0].unsubscribed).toBe(true);
    expect(conn.subscriptionCount).toBe(1);

    rosList[0].emit('close');
    timers.runNext();
    await flush();
    rosList[1].emit('connection');
    await flush();
    // Only /other is re-subscribed, on the new socket.
    expect(topics.map((t) => t.name)).toEqual(['/cell/mode', '/other', '/other']);
    expect(topics[2].ros).toBe(rosList[1]);
    topics[2].deliver({ data: 'x' });
    expect(got).toEqual([['a', 'running'], ['b', 'x']]);
  });

  it('a subscription made while connected attaches immediately', async () => {
    const { conn, rosList, topics } = setup();
    conn.start();
    await flush();
    rosList[0].emit('connection');
    conn.subscribe('/late', 'std_msgs/String', () => {});
    await flush();
    expect(topics.map((t) => t.name)).toEqual(['/late']);
  });

  it('ignores events from a dead socket', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    const old = rosList[0];
    old.emit('close');
    timers.runNext();
    await flush();
    old.emit('connection'); // late event from the first socket
    expect(conn.state).toBe('connecting');
    old.emit('close');
    expect(timers.pending).toHaveLength(0);
  });

  it('stop() closes the socket and does not reconnect (logout)', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    rosList[0].emit('connection');
    conn.stop();
    expect(rosList[0].closed).toBe(true);
    expect(conn.state).toBe('disconnected');
    rosList[0].emit('close');
    expect(timers.pending).toHaveLength(0);
  });

  it('stop() during a backoff wait cancels the retry', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    rosList[0].emit('close');
    expect(timers.pending).toHaveLength(1);
    conn.stop();
    expect(timers.pending).toHaveLength(0);
  });

  it('retryNow() skips the backoff wait and resets the delay', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    rosList[0].emit('close');
    timers.runNext();
    await flush();
    rosList[1].emit('close'); // now waiting 1 s
    expect(timers.pending[0].ms).toBe(1000);
    conn.retryNow();
    expect(timers.pending).toHaveLength(0);
    expect(conn.state).toBe('connecting');
    await flush();
    expect(rosList).toHaveLength(3);
    rosList[2].emit('close');
    expect(timers.pending[0].ms).toBe(500);
  });
});
