import { describe, it, expect, vi } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import LeaseBar from '../../src/lib/ui/LeaseBar.svelte';
import { ControlLease } from '../../src/lib/core/lease.svelte.js';
import { makeFakeTimers, flush } from '../fakeRos.js';

const ann = { username: 'ann', role: 'operator', since: '2024-01-01T10:00:00.000Z' };
const boss = { username: 'boss', role: 'admin', since: '2024-01-01T10:05:00.000Z' };
/** @param {any} data @returns {any} */
const ok = (data) => ({ kind: 'ok', status: 200, data });

/** @param {any} [view] */
function setup(view = { holder: null, you: false }) {
  /** @type {Record<string, any>} */
  const answers = {
    control: ok(view),
    controlTake: ok({ holder: ann, you: true }),
    controlHeartbeat: ok({ holder: ann, you: true }),
    controlRelease: { kind: 'ok', status: 204, data: null },
  };
  const api = /** @type {any} */ ({});
  for (const k of Object.keys(answers)) api[k] = vi.fn(async () => answers[k]);
  const timers = makeFakeTimers();
  const lease = new ControlLease({ api, setTimer: timers.setTimer, clearTimer: timers.clearTimer });
  return { lease, api, answers, timers };
}

describe('LeaseBar', () => {
  it('nobody holds control: "Take control" takes it, then "Release control" gives it back', async () => {
    const { lease, api } = setup();
    render(LeaseBar, { lease });
    await flush();
    flushSync();
    expect(screen.getByTestId('lease-holder').textContent).toContain('Nobody has control');
    await fireEvent.click(screen.getByRole('button', { name: 'Take control' }));
    await vi.waitFor(() => expect(screen.getByTestId('lease-holder').textContent).toContain('You have control'));
    expect(api.controlTake).toHaveBeenCalledTimes(1);
    await fireEvent.click(screen.getByRole('button', { name: 'Release control' }));
    await vi.waitFor(() => expect(screen.getByRole('button', { name: 'Take control' })).toBeTruthy());
    expect(api.controlRelease).toHaveBeenCalledTimes(1);
  });

  it('everyone sees who holds control; without take-over the take button is off and says why', async () => {
    const { lease } = setup({ holder: ann, you: false });
    render(LeaseBar, { lease, takeOver: false });
    await flush();
    flushSync();
    expect(screen.getByTestId('lease-holder').textContent).toContain('ann (operator) has control');
    const take = /** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Take control' }));
    expect(take.disabled).toBe(true);
    expect(screen.getByTestId('lease-take-feedback').textContent).toContain('ann (operator) has control');
    expect(screen.queryByRole('button', { name: 'Take over control' })).toBeNull();
  });

  it('a role that may take over gets "Take over control", which sends force', async () => {
    const { lease, api, answers } = setup({ holder: ann, you: false });
    answers.controlTake = ok({ holder: boss, you: true });
    render(LeaseBar, { lease, takeOver: true });
    await flush();
    flushSync();
    await fireEvent.click(screen.getByRole('button', { name: 'Take over control' }));
    expect(api.controlTake).toHaveBeenCalledWith({ force: true });
    await vi.waitFor(() => expect(screen.getByTestId('lease-holder').textContent).toContain('You have control'));
  });

  it('a refused take shows the server message', async () => {
    const { lease, answers } = setup();
    answers.controlTake = { kind: 'error', status: 409, error: 'control is held by ann (operator)', data: { holder: ann } };
    render(LeaseBar, { lease });
    await flush();
    await fireEvent.click(screen.getByRole('button', { name: 'Take control' }));
    await vi.waitFor(() => expect(screen.getByTestId('lease-take-feedback').textContent).toContain('control is held by ann (operator)'));
  });

  it('shows a lost-lease notice when control is taken over, until dismissed', async () => {
    const { lease, answers, timers } = setup();
    render(LeaseBar, { lease });
    await flush();
    await fireEvent.click(screen.getByRole('button', { name: 'Take control' }));
    await vi.waitFor(() => expect(lease.you).toBe(true));
    answers.controlHeartbeat = { kind: 'error', status: 409, error: 'you do not hold control', data: { holder: boss } };
    timers.runNext();
    await flush();
    flushSync();
    expect(screen.getByRole('alert').textContent).toContain('Control lost: taken over by boss (admin).');
    await fireEvent.click(screen.getByRole('button', { name: 'Dismiss the control notice' }));
    expect(screen.queryByTestId('lease-lost')).toBeNull();
  });

  it('offline: the buttons are off, with the reason', async () => {
    const { lease } = setup();
    render(LeaseBar, { lease, offline: true });
    await flush();
    const take = /** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Take control' }));
    expect(take.disabled).toBe(true);
    expect(screen.getByTestId('lease-take-feedback').textContent).toContain('Offline');
  });

  it('stops polling when it is removed', async () => {
    const { lease, timers } = setup();
    const { unmount } = render(LeaseBar, { lease });
    await flush();
    expect(timers.pending).toHaveLength(1);
    unmount();
    expect(timers.pending).toHaveLength(0);
  });
});

describe('LeaseBar and the heartbeat', () => {
  it('leaving the page while holding control keeps the heartbeat going', async () => {
    const { lease, timers } = setup();
    const { unmount } = render(LeaseBar, { lease });
    await flush();
    await fireEvent.click(screen.getByRole('button', { name: 'Take control' }));
    await vi.waitFor(() => expect(lease.you).toBe(true));
    unmount();
    expect(timers.pending.map((p) => p.ms)).toEqual([500]);
  });
});
