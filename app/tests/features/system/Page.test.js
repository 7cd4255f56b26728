import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen } from '@testing-library/svelte';
import SystemPage from '../../../src/lib/features/system/Page.svelte';
import HealthPanel from '../../../src/lib/features/system/HealthPanel.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { lastKnown } from '../../../src/lib/core/lastKnown.js';

const feature = { id: 'system', path: '/system', title: 'System', icon: '', load: async () => ({ default: SystemPage }) };
const overview = {
  cell_file: '/repo/config/demo-cell.yaml',
  cell: { id: 'demo', name: 'Demo cell', description: '' },
  roles: [{ name: 'admin', pages: ['home', 'system'] }],
  users: [{ username: 'admin', role: 'admin' }, { username: 'operator', role: 'operator' }],
  health: { status: 'ok', ros: { rosbridge: true, master: true }, uptime_s: 61, version: '0.1.0' },
};

beforeEach(async () => {
  session.user = { username: 'admin', role: 'admin' };
  session.offline = false;
  await lastKnown.clear();
});
afterEach(() => vi.unstubAllGlobals());

describe('System page', () => {
  it('shows health with its age, the cell file, roles and users, and keeps them', async () => {
    vi.stubGlobal('fetch', vi.fn(async () => new Response(JSON.stringify(overview), { status: 200 })));
    render(SystemPage, { feature });
    await vi.waitFor(() => expect(screen.getByTestId('system-cell-file').textContent).toBe('/repo/config/demo-cell.yaml'));
    await vi.waitFor(() => expect(screen.getByTestId('system-users').textContent).toContain('operator'));
    expect(screen.getByTestId('system-health').textContent).toContain('rosbridge');
    expect(screen.getByTestId('system-health-freshness-age').textContent).toBe('updated just now');
    await vi.waitFor(async () => expect((await lastKnown.load('system', { user: 'admin' }))?.data.cell_file).toBe(overview.cell_file));
  });

  it('offline: shows the last known state with its age, health marked unreachable', async () => {
    await lastKnown.save('system', overview, { user: 'admin', savedAt: Date.now() - 5 * 60_000 });
    vi.stubGlobal('fetch', vi.fn(async () => { throw new TypeError('Failed to fetch'); }));
    render(SystemPage, { feature });
    await vi.waitFor(() => expect(screen.getByTestId('system-users').textContent).toContain('operator'));
    expect(screen.getByTestId('last-known').textContent).toMatch(/Offline.*from 5 min ago/);
    expect(screen.getByTestId('system-health-freshness').dataset.stale).toBe('true');
    expect(screen.getByTestId('system-health').textContent).toContain('unreachable');
    expect(session.offline).toBe(true);
  });

  it('403: access denied, nothing shown', async () => {
    vi.stubGlobal('fetch', vi.fn(async () => new Response(JSON.stringify({ error: 'no' }), { status: 403 })));
    render(SystemPage, { feature });
    expect(await screen.findByTestId('access-denied')).toBeTruthy();
    expect(screen.queryByTestId('system-users')).toBeNull();
  });
});

describe('HealthPanel', () => {
  it('greys and labels health values older than two polls', () => {
    render(HealthPanel, { health: overview.health, at: 0, now: 60_000 });
    expect(screen.getByTestId('system-health-freshness-age').textContent).toBe('stale · 1 min ago');
  });
});
