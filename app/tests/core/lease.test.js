// @vitest-environment node
import { describe, it, expect, vi } from 'vitest';
import { ControlLease, holderLabel } from '../../src/lib/core/lease.svelte.js';
import { makeFakeTimers, flush } from '../fakeRos.js';

const ann = { username: 'ann', role: 'operator', since: '2024-01-01T10:00:00.000Z' };
const boss = { username: 'boss', role: 'admin', since: '2024-01-01T10:05:00.000Z' };
/** @param {any} data @returns {any} */
const ok = (data) => ({ kind: 'ok', status: 200, data });
/** @param {string} error @param {any} holder @returns {any} */
const conflict = (error, holder) => ({ kind: 'error', status: 409, error, data: { error, holder } });
/** @type {any} */
const offline = { kind: 'offline', error: 'Failed to fetch' };

/** A fake control API whose answers the test sets; records the calls. */
function fakeApi() {
  /** @type {Record<string, any>} */
  const answers = {
    control: ok({ holder: null, you: false }),
    controlTake: ok({ holder: ann, you: true }),
    controlHeartbeat: ok({ holder: ann, you: true }),
    controlRelease: { kind: 'ok', status: 204, data: null },
  };
  /** @type {string[]} */
  const calls = [];
  const api = /** @type {any} */ ({});
  for (const k of Object.keys(answers)) {
    api[k] = vi.fn(async (/** @type {any} */ arg) => {
      calls.push(arg?.force ? `${k}(force)` : typeof arg === 'number' ? `${k}(${arg} ms)` : k);
      return answers[k];
    });
  }
  return { api, answers, calls };
}

function setup() {
  const f = fakeApi();
  const timers = makeFakeTimers();
  let t = 1_000_000;
  const clock = { now: () => t, advance: (/** @type {number} */ ms) => (t += ms) };
  const onUnauthorized = vi.fn();
  const lease = new ControlLease({ api: f.api, setTimer: timers.setTimer, clearTimer: timers.clearTimer, now: clock.now, onUnauthorized });
  /** Run the next timer and let its request be answered. */
  const step = async () => {
    const ms = timers.runNext();
    clock.advance(ms);
    await flush();
    return ms;
  };
  return { ...f, timers, clock, lease, step, onUnauthorized };
}

describe('ControlLease', () => {
  it('polls who holds control about every 1.5 s while watched, and stops when nobody watches', async () => {
    const { lease, answers, calls, timers, step } = setup();
    answers.control = ok({ holder: ann, you: false });
    const unwatch = lease.watch();
    await flush();
    expect(lease.holder).toEqual(ann);
    expect(lease.you).toBe(false);
    expect(lease.reachable).toBe(true);
    expect(timers.pending.map((p) => p.ms)).toEqual([1500]);
    await step();
    expect(calls).toEqual(['control', 'control']);
    unwatch();
    expect(timers.pending).toHaveLength(0);
  });

  it('take -> heartbeat every 500 ms while held -> release (204) -> back to polling', async () => {
    const { lease, calls, timers, step } = setup();
    lease.watch();
    await flush();
    await lease.take();
    expect(lease.you).toBe(true);
    expect(lease.holder).toEqual(ann);
    expect(timers.pending.map((p) => p.ms)).toEqual([500]);
    expect(await step()).toBe(500);
    expect(await step()).toBe(500);
    // Each heartbeat gives up after half the 2 s lease timeout, so one that hangs does not hold back the next.
    expect(calls).toEqual(['control', 'controlTake', 'controlHeartbeat(1000 ms)', 'controlHeartbeat(1000 ms)']);
    await lease.release();
    await flush();
    expect(lease.you).toBe(false);
    expect(lease.holder).toBeNull();
    expect(lease.lost).toBeNull();
    expect(calls.slice(4)).toEqual(['controlRelease', 'control']);
    expect(timers.pending.map((p) => p.ms)).toEqual([1500]);
  });

  it('heartbeats go on without anyone watching (the lease belongs to the session, not the page)', async () => {
    const { lease, timers, step } = setup();
    const unwatch = lease.watch();
    await flush();
    await lease.take();
    unwatch();
    expect(timers.pending.map((p) => p.ms)).toEqual([500]);
    await step();
    expect(timers.pending.map((p) => p.ms)).toEqual([500]);
  });

  it('a refused take throws the server message and shows the holder', async () => {
    const { lease, answers } = setup();
    answers.controlTake = conflict('control is held by ann (operator)', { username: 'ann', role: 'operator' });
    await expect(lease.take()).rejects.toThrow('control is held by ann (operator)');
    expect(lease.you).toBe(false);
    expect(lease.holder).toEqual({ username: 'ann', role: 'operator' });
  });

  it('take-over sends force', async () => {
    const { lease, answers, calls } = setup();
    answers.controlTake = ok({ holder: boss, you: true });
    await lease.take({ force: true });
    expect(calls).toEqual(['controlTake(force)']);
    expect(lease.you).toBe(true);
  });

  it('a heartbeat answered 409 means someone took control over: lost notice names them', async () => {
    const { lease, answers, timers, step } = setup();
    await lease.take();
    answers.controlHeartbeat = conflict('you do not hold control', boss);
    await step();
    expect(lease.you).toBe(false);
    expect(lease.holder).toEqual(boss);
    expect(lease.lost?.reason).toBe('taken over by boss (admin)');
    // Not watched: no more requests.
    expect(timers.pending).toHaveLength(0);
    lease.dismissLost();
    expect(lease.lost).toBeNull();
  });

  it('a heartbeat answered 409 with no holder means the lease expired', async () => {
    const { lease, answers, step } = setup();
    await lease.take();
    answers.controlHeartbeat = conflict('you do not hold control', null);
    await step();
    expect(lease.lost?.reason).toMatch(/^the lease expired/);
  });

  it('a server back from a restart in time gives control back: a kept notice, once, heartbeats go on', async () => {
    const { lease, answers, step, calls } = setup();
    await lease.take();
    answers.controlHeartbeat = offline;
    await step();
    await step();
    expect(lease.you).toBe(true);
    expect(lease.kept).toBeNull();
    answers.controlHeartbeat = ok({ holder: { ...ann, resumed_at: '2024-01-01T10:09:00.000Z' }, you: true });
    await step();
    expect(lease.you).toBe(true);
    expect(lease.kept?.reason).toMatch(/^the server restarted and gave control back to you/);
    lease.dismissKept();
    await step();
    expect(lease.kept).toBeNull(); // the same restart is told once
    expect(calls.filter((c) => c.startsWith('controlHeartbeat'))).toHaveLength(4);
    answers.controlHeartbeat = ok({ holder: { ...ann, resumed_at: '2024-01-01T10:19:00.000Z' }, you: true });
    await step();
    expect(lease.kept).not.toBeNull(); // another restart
    await lease.release();
    expect(lease.kept).toBeNull(); // nothing kept any more once released
  });

  it('a server that restarts slower than the timeout: control reads lost, then kept when it answers that it gave it back', async () => {
    const { lease, answers, step } = setup();
    await lease.take();
    answers.controlHeartbeat = offline;
    for (let i = 0; i < 5; i++) await step(); // 2.5 s
    expect(lease.you).toBe(false);
    expect(lease.lost?.reason).toBe('the server could not be reached');
    await step(); // still asking
    answers.controlHeartbeat = ok({ holder: { ...ann, resumed_at: '2024-01-01T10:09:00.000Z' }, you: true });
    await step();
    expect(lease.you).toBe(true);
    expect(lease.lost).toBeNull();
    expect(lease.kept?.reason).toMatch(/^the server restarted and gave control back to you/);
  });

  it('after losing control to an unreachable server: a 409 gives the server\'s reason; silence ends the asking', async () => {
    const { lease, answers, step, timers, calls } = setup();
    await lease.take();
    answers.controlHeartbeat = offline;
    for (let i = 0; i < 5; i++) await step();
    const ended = 'control lapsed while the server restarted (it was back 3.4 s after the last heartbeat; the limit is 2 s)';
    answers.controlHeartbeat = { kind: 'error', status: 409, error: 'you do not hold control', data: { error: 'you do not hold control', holder: null, ended } };
    await step();
    expect(lease.you).toBe(false);
    expect(lease.lost?.reason).toBe(ended);
    expect(timers.pending).toHaveLength(0); // not watched, not reclaiming: no more requests

    await lease.take();
    answers.controlHeartbeat = offline;
    for (let i = 0; i < 5; i++) await step();
    const before = calls.length;
    for (let i = 0; i < 80 && timers.pending.length; i++) await step(); // 30 s of asking, then it stops
    expect(timers.pending).toHaveLength(0);
    expect(calls.length - before).toBe(61); // every 0.5 s from 0 to 30 s
    expect(lease.lost?.reason).toBe('the server could not be reached');
  });

  it('a heartbeat answered 409 with the server\'s reason (control lapsed during a restart) shows that reason', async () => {
    const { lease, answers, step } = setup();
    await lease.take();
    const ended = 'control lapsed while the server restarted (it was back 5.2 s after the last heartbeat; the limit is 2 s)';
    answers.controlHeartbeat = { kind: 'error', status: 409, error: 'you do not hold control', data: { error: 'you do not hold control', holder: null, ended } };
    await step();
    expect(lease.you).toBe(false);
    expect(lease.lost?.reason).toBe(ended);
  });

  it('offline heartbeats lose control once the server timeout has passed', async () => {
    const { lease, answers, step } = setup();
    await lease.take();
    answers.controlHeartbeat = offline;
    await step(); // 0.5 s
    await step(); // 1.0 s
    await step(); // 1.5 s
    await step(); // 2.0 s
    expect(lease.you).toBe(true);
    expect(lease.reachable).toBe(false);
    await step(); // 2.5 s > 2 s
    expect(lease.you).toBe(false);
    expect(lease.lost?.reason).toBe('the server could not be reached');
  });

  it('a poll that no longer shows us as holder reports the loss', async () => {
    const { lease, answers } = setup();
    answers.control = ok({ holder: ann, you: true });
    lease.watch();
    await flush();
    expect(lease.you).toBe(true); // e.g. a reload within the timeout: we resume heartbeats
    answers.control = ok({ holder: boss, you: false });
    await lease.refresh();
    expect(lease.lost?.reason).toBe('taken over by boss (admin)');
  });

  it('taking control again clears the lost notice', async () => {
    const { lease, answers, step } = setup();
    await lease.take();
    answers.controlHeartbeat = conflict('x', null);
    await step();
    expect(lease.lost).not.toBeNull();
    await lease.take();
    expect(lease.lost).toBeNull();
  });

  it('releaseBecause leaves a notice saying why; reset forgets everything and stops the timers', async () => {
    const { lease, timers, calls } = setup();
    lease.watch();
    await flush();
    await lease.take();
    await lease.releaseBecause('released when the app was hidden');
    expect(calls).toContain('controlRelease');
    expect(lease.lost?.reason).toBe('released when the app was hidden');
    lease.reset();
    expect(lease.lost).toBeNull();
    expect(timers.pending).toHaveLength(0);
  });

  it('a 401 on any lease call ends the session', async () => {
    const { lease, answers, onUnauthorized } = setup();
    answers.control = { kind: 'unauthorized', status: 401, error: 'Not logged in' };
    await lease.refresh();
    expect(onUnauthorized).toHaveBeenCalledTimes(1);
  });

  it('offline: take fails with a message, the holder is unknown', async () => {
    const { lease, answers } = setup();
    answers.control = offline;
    answers.controlTake = offline;
    await lease.refresh();
    expect(lease.reachable).toBe(false);
    await expect(lease.take()).rejects.toThrow(/Offline/);
  });

  it('labels a holder', () => {
    expect(holderLabel(ann)).toBe('ann (operator)');
    expect(holderLabel(null)).toBe('nobody');
  });

  it('follows the cell\'s lease timeout: each heartbeat gives up after half of it', async () => {
    const { lease, calls, step } = setup();
    lease.configure(5);
    lease.configure('nonsense'); // ignored
    lease.configure(0); // ignored
    await lease.take();
    await step();
    expect(calls).toEqual(['controlTake', 'controlHeartbeat(2500 ms)']);
    expect(lease.timeoutMs).toBe(5000);
  });
});
