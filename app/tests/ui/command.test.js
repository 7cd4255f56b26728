// @vitest-environment node
import { describe, it, expect } from 'vitest';
import { Command, expectSuccess, errorMessage } from '../../src/lib/ui/command.svelte.js';
import { makeFakeTimers } from '../fakeRos.js';

describe('Command', () => {
  it('pending -> done -> idle after a while', async () => {
    const timers = makeFakeTimers();
    const c = new Command({ doneMs: 4000, setTimer: timers.setTimer, clearTimer: timers.clearTimer });
    /** @type {(v: any) => void} */
    let finish = () => {};
    const p = c.run(() => new Promise((r) => (finish = r)));
    expect(c.status).toBe('pending');
    finish(42);
    expect(await p).toBe(42);
    expect(c.status).toBe('done');
    expect(timers.runNext()).toBe(4000);
    expect(c.status).toBe('idle');
  });

  it("failed keeps the backend's message until dismissed or run again", async () => {
    const c = new Command();
    expect(await c.run(async () => { throw new Error('permission denied: /cell/stop'); })).toBeUndefined();
    expect(c.status).toBe('failed');
    expect(c.message).toBe('permission denied: /cell/stop');
    c.dismiss();
    expect(c.status).toBe('idle');
    expect(c.message).toBe('');
  });

  it('a second press while pending is ignored: nothing piles up', async () => {
    const c = new Command();
    let n = 0;
    /** @type {() => void} */
    let finish = () => {};
    const first = c.run(() => { n++; return new Promise((r) => (finish = () => r(undefined))); });
    expect(await c.run(() => n++)).toBeUndefined();
    expect(n).toBe(1);
    finish();
    await first;
  });

  it('expectSuccess turns a Trigger refusal into a failure with its message', () => {
    expect(expectSuccess({ success: true, message: '' })).toEqual({ success: true, message: '' });
    expect(() => expectSuccess({ success: false, message: 'driver not ready' })).toThrow('driver not ready');
    expect(() => expectSuccess({ success: false })).toThrow('The robot refused the command');
    expect(errorMessage('x')).toBe('x');
    expect(errorMessage(undefined)).toBe('The command failed');
  });
});
