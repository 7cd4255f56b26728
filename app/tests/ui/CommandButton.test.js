import { describe, it, expect, vi } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import CommandButton from '../../src/lib/ui/CommandButton.svelte';

describe('CommandButton', () => {
  it('shows pending, then done', async () => {
    /** @type {() => void} */
    let finish = () => {};
    const run = vi.fn(() => new Promise((r) => (finish = () => r(undefined))));
    render(CommandButton, { label: 'Reset alarms', run, pendingText: 'Resetting…', doneText: 'Alarms reset', testid: 'reset' });
    const btn = screen.getByRole('button', { name: 'Reset alarms' });
    await fireEvent.click(btn);
    expect(run).toHaveBeenCalledTimes(1);
    expect(btn.getAttribute('aria-busy')).toBe('true');
    expect(screen.getByTestId('reset-feedback').textContent).toContain('Resetting…');
    // A second tap while pending sends nothing.
    await fireEvent.click(btn);
    expect(run).toHaveBeenCalledTimes(1);
    finish();
    await vi.waitFor(() => expect(screen.getByTestId('reset-feedback').textContent).toContain('Alarms reset'));
    expect(btn.getAttribute('data-status')).toBe('done');
  });

  it("shows the backend's message when the command fails, and can dismiss it", async () => {
    const run = vi.fn(async () => {
      throw new Error('permission denied: role "operator" may not call /cell/alarms/reset');
    });
    render(CommandButton, { label: 'Reset alarms', run, testid: 'reset' });
    await fireEvent.click(screen.getByRole('button', { name: 'Reset alarms' }));
    const fb = screen.getByTestId('reset-feedback');
    await vi.waitFor(() => expect(fb.textContent).toContain('Failed: permission denied: role "operator" may not call /cell/alarms/reset'));
    await fireEvent.click(screen.getByRole('button', { name: 'Dismiss the message about Reset alarms' }));
    expect(fb.textContent?.trim()).toBe('');
  });

  it('is disabled with its reason when the gate is closed, and sends nothing', async () => {
    const run = vi.fn();
    render(CommandButton, { label: 'Reset alarms', run, gate: { ok: false, reason: 'Offline: commands are unavailable' }, testid: 'reset' });
    const btn = /** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Reset alarms' }));
    expect(btn.disabled).toBe(true);
    expect(screen.getByTestId('reset-feedback').textContent).toContain('Offline: commands are unavailable');
    // The reason is the button's description for screen readers.
    expect(document.getElementById(/** @type {string} */ (btn.getAttribute('aria-describedby')))?.textContent).toContain('Offline');
    await fireEvent.click(btn);
    expect(run).not.toHaveBeenCalled();
  });

  it('an aria-label overrides the visible text as the accessible name', () => {
    render(CommandButton, { label: 'Go', ariaLabel: 'Start the process', run: () => {} });
    expect(screen.getByRole('button', { name: 'Start the process' })).toBeTruthy();
  });
});
