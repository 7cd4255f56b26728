import { describe, it, expect, vi } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import StopButton from '../../src/lib/ui/StopButton.svelte';
import TopBar from '../../src/lib/ui/TopBar.svelte';
import TopBarWithStop from '../fixtures/TopBarWithStop.svelte';
import { RosConnection } from '../../src/lib/core/connection.svelte.js';
import { fakeConnection } from '../fakeRos.js';

const stop = { service: '/cell/robot/stop', type: 'std_srvs/Trigger' };

describe('StopButton', () => {
  it('is named exactly "Stop robot" and calls the stop service with no lease', async () => {
    const call = vi.fn(async () => ({ success: true, message: 'stopped' }));
    render(StopButton, { stop, call });
    await fireEvent.click(screen.getByRole('button', { name: 'Stop robot' }));
    expect(call).toHaveBeenCalledWith('/cell/robot/stop', 'std_srvs/Trigger', {}, { timeoutMs: 3000 });
    await vi.waitFor(() => expect(screen.getByTestId('stop-robot-feedback').textContent).toContain('Stop sent'));
  });

  it('a refused or failed stop is shown with the message', async () => {
    const call = vi.fn(async () => ({ success: false, message: 'driver not connected' }));
    render(StopButton, { stop, call });
    await fireEvent.click(screen.getByRole('button', { name: 'Stop robot' }));
    await vi.waitFor(() => expect(screen.getByTestId('stop-robot-feedback').textContent).toContain('Stop failed: driver not connected'));
  });

  it('defaults the type to std_srvs/Trigger', async () => {
    const call = vi.fn(async () => ({ success: true }));
    render(StopButton, { stop: { service: '/s' }, call });
    await fireEvent.click(screen.getByRole('button', { name: 'Stop robot' }));
    expect(call).toHaveBeenCalledWith('/s', 'std_srvs/Trigger', {}, { timeoutMs: 3000 });
  });

  it('is not drawn without a stop service (stop: null: a role with no page, or a cell without a robot stop)', () => {
    render(StopButton, { stop: null, call: vi.fn() });
    expect(screen.queryByRole('button', { name: 'Stop robot' })).toBeNull();
  });

  it('is disabled while disconnected: nothing is queued', async () => {
    const call = vi.fn();
    render(StopButton, { stop, call, gate: { ok: false, reason: 'Not connected to ROS' } });
    const btn = /** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Stop robot' }));
    expect(btn.disabled).toBe(true);
    await fireEvent.click(btn);
    expect(call).not.toHaveBeenCalled();
  });

  it('sits in the top bar, next to the page title', () => {
    const call = vi.fn();
    render(TopBarWithStop, { stop, call });
    const bar = screen.getByRole('banner');
    expect(bar.querySelector('[data-testid="page-title"]')?.textContent).toBe('Home');
    expect(bar.contains(screen.getByRole('button', { name: 'Stop robot' }))).toBe(true);
  });

  it('the top bar has no stop without one', () => {
    render(TopBar, { title: 'Home' });
    expect(screen.queryByRole('button', { name: 'Stop robot' })).toBeNull();
  });

  it('over the shared connection: the Trigger call goes out on the socket, its refusal is shown', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    render(StopButton, { stop, call: (/** @type {any[]} */ ...a) => t.conn.callService(a[0], a[1], a[2], a[3]) });
    await fireEvent.click(screen.getByRole('button', { name: 'Stop robot' }));
    expect(t.calls).toHaveLength(1);
    expect(t.calls[0]).toMatchObject({ name: '/cell/robot/stop', type: 'std_srvs/Trigger', args: {} });
    t.calls[0].fail('permission denied: /cell/robot/stop');
    await vi.waitFor(() => expect(screen.getByTestId('stop-robot-feedback').textContent).toContain('Stop failed: permission denied: /cell/robot/stop'));
  });

  it('over the shared connection: no answer within 3 s is a failure', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    render(StopButton, { stop, call: (/** @type {any[]} */ ...a) => t.conn.callService(a[0], a[1], a[2], a[3]) });
    await fireEvent.click(screen.getByRole('button', { name: 'Stop robot' }));
    expect(t.timers.pending.map((p) => p.ms)).toEqual([3000]);
    t.timers.runNext();
    await vi.waitFor(() => expect(screen.getByTestId('stop-robot-feedback').textContent).toContain('No answer from /cell/robot/stop within 3 s'));
  });
});
