import { describe, it, expect } from 'vitest';
import { render, screen } from '@testing-library/svelte';
import { createRawSnippet } from 'svelte';
import LiveValue from '../../src/lib/ui/LiveValue.svelte';
import LastKnownNotice from '../../src/lib/ui/LastKnownNotice.svelte';

const value = createRawSnippet(() => ({ render: () => '<span>42 N</span>' }));

describe('LiveValue', () => {
  it('shows the age of a fresh value', () => {
    render(LiveValue, { at: 10_000, periodMs: 5000, now: 13_000, testid: 'v', children: value });
    expect(screen.getByTestId('v').dataset.stale).toBe('false');
    expect(screen.getByTestId('v-age').textContent).toBe('updated 3 s ago');
    expect(screen.getByText('42 N')).toBeTruthy();
  });

  it('marks an old value stale, in words and not only in grey', () => {
    render(LiveValue, { at: 10_000, periodMs: 5000, now: 70_000, testid: 'v', children: value });
    expect(screen.getByTestId('v').dataset.stale).toBe('true');
    expect(screen.getByTestId('v').className).toContain('stale');
    expect(screen.getByTestId('v-age').textContent).toBe('stale · 1 min ago');
  });

  it('an event-driven value is "live" while its link is up, stale when not', () => {
    const { unmount } = render(LiveValue, { at: null, periodMs: 0, live: true, testid: 'v', children: value });
    expect(screen.getByTestId('v-age').textContent).toBe('live');
    unmount();
    render(LiveValue, { at: Date.now() - 5000, periodMs: 0, live: false, testid: 'v', children: value });
    expect(screen.getByTestId('v-age').textContent).toMatch(/^stale · \d s ago$/);
  });
});

describe('LastKnownNotice', () => {
  it('says why and how old', () => {
    render(LastKnownNotice, { why: 'offline', savedAt: 0, now: 120_000 });
    expect(screen.getByTestId('last-known').textContent).toMatch(/Offline.*last known state, from 2 min ago.*Commands are unavailable/s);
  });

  it('says when nothing was saved; shows nothing while live', () => {
    const { unmount } = render(LastKnownNotice, { why: 'disconnected', savedAt: null });
    expect(screen.getByTestId('last-known').textContent).toContain('ROS disconnected');
    expect(screen.getByTestId('last-known').textContent).toContain('no saved state');
    unmount();
    render(LastKnownNotice, { why: null, savedAt: 1 });
    expect(screen.queryByTestId('last-known')).toBeNull();
  });
});
