// @vitest-environment node
import { describe, it, expect, vi } from 'vitest';
import { HeartbeatLoop } from '../../src/lib/core/lease-beat.js';
import { ControlLease } from '../../src/lib/core/lease.svelte.js';
import { makeFakeTimers, flush } from '../fakeRos.js';

function setup() {
  const timers = makeFakeTimers();
  let t = 0;
  const clock = { now: () => t, advance: (/** @type {number} */ ms) => (t += ms) };
  /** @type {number[]} */
  const sent = [];
  const loop = new HeartbeatLoop({
    send: async (ms) => {
      sent.push(ms);
      return `answer ${sent.length}`;
    },
    setTimer: timers.setTimer,
    clearTimer: timers.clearTimer,
    now: clock.now,
  });
  /** Let the next timer's time pass, run it, and let its request be answered. */
  const step = async () => {
    clock.advance(timers.pending[0].ms);
    timers.runNext();
    await flush();
  };
  return { timers, clock, sent, loop, step };
}

describe('HeartbeatLoop', () => {
  it('beats every interval (the first after one) with the request timeout, and hands each answer over', async () => {
    const { loop, sent, step, timers } = setup();
    /** @type {string[]} */
    const answers = [];
    loop.start({ intervalMs: 500, timeoutMs: 1000 }, (a) => answers.push(a));
    expect(sent).toEqual([]);
    expect(timers.pending.map((p) => p.ms)).toEqual([500]);
    await step();
    await step();
    expect(sent).toEqual([1000, 1000]);
    expect(answers).toEqual(['answer 1', 'answer 2']);
    loop.stop();
    expect(timers.pending).toEqual([]);
  });

  it('a page that took no answer for stallMs gets no more heartbeats (a hung page loses control); one that answers again does', async () => {
    const { loop, sent, step, clock } = setup();
    loop.start({ intervalMs: 500, timeoutMs: 1000, stallMs: 2000 }, () => {}); // no ack: the page hangs
    for (let i = 0; i < 4; i++) await step(); // 2 s: still beating
    expect(sent).toHaveLength(4);
    for (let i = 0; i < 4; i++) await step();
    expect(sent).toHaveLength(4);
    expect(loop.stalled).toBe(true);
    loop.ack();
    await step();
    expect(sent).toHaveLength(5);
    expect(clock.now()).toBe(4500);
  });

  it('a page that takes each answer is never stalled, however long it holds control', async () => {
    const { loop, sent, step } = setup();
    loop.start({ intervalMs: 500, timeoutMs: 1000, stallMs: 2000 }, () => loop.ack());
    for (let i = 0; i < 20; i++) await step();
    expect(sent).toHaveLength(20);
  });

  it('an answer that comes after stop (or a new start) is dropped', async () => {
    const timers = makeFakeTimers();
    /** @type {(v: string) => void} */
    let answer = () => {};
    const loop = new HeartbeatLoop({ send: () => new Promise((r) => (answer = r)), setTimer: timers.setTimer, clearTimer: timers.clearTimer });
    const onAnswer = vi.fn();
    loop.start({ intervalMs: 500, timeoutMs: 1000 }, onAnswer);
    timers.runNext();
    loop.stop();
    answer('late');
    await flush();
    expect(onAnswer).not.toHaveBeenCalled();
    expect(timers.pending).toEqual([]);
  });
});

describe('ControlLease with its own beater', () => {
  it('starts the heartbeats when it takes control, hands their answers to the lease, and stops them on release', async () => {
    const holder = { username: 'ann', role: 'admin' };
    /** @type {any} */
    const api = {
      control: async () => ({ kind: 'ok', status: 200, data: { holder: null, you: false } }),
      controlTake: async () => ({ kind: 'ok', status: 200, data: { holder, you: true } }),
      controlHeartbeat: vi.fn(),
      controlRelease: async () => ({ kind: 'ok', status: 204, data: null }),
    };
    /** @type {any[]} */
    const log = [];
    /** @type {(r: any) => void} */
    let hand = () => {};
    const beater = {
      start: (/** @type {any} */ o, /** @type {any} */ onAnswer) => {
        log.push(['start', o]);
        hand = onAnswer;
      },
      stop: () => log.push(['stop']),
      ack: () => log.push(['ack']),
    };
    const lease = new ControlLease({ api, beater });
    await lease.take();
    expect(log).toEqual([['start', { intervalMs: 500, timeoutMs: 1000, stallMs: 2000 }]]);
    hand({ kind: 'ok', status: 200, data: { holder, you: true } });
    expect(lease.you).toBe(true);
    expect(log.at(-1)).toEqual(['ack']);
    // Someone took over: the answer ends our control, and the heartbeats stop.
    hand({ kind: 'error', status: 409, error: 'held', data: { holder: { username: 'boss', role: 'admin' } } });
    expect(lease.you).toBe(false);
    expect(lease.lost?.reason).toMatch(/boss/);
    expect(log.at(-1)).toEqual(['stop']);
    await lease.take();
    expect(log.at(-1)[0]).toBe('start');
    await lease.release();
    expect(log.at(-1)).toEqual(['stop']);
    expect(api.controlHeartbeat).not.toHaveBeenCalled();
  });
});
