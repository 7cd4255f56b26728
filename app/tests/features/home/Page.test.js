import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import HomePage from '../../../src/lib/features/home/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { opMode } from '../../../src/lib/core/opMode.svelte.js';
import { lease } from '../../../src/lib/core/lease.svelte.js';
import { lastKnown } from '../../../src/lib/core/lastKnown.js';
import { makeFakeFactory, flush } from '../../fakeRos.js';

const feature = { id: 'home', path: '/', title: 'Home', icon: '', load: async () => ({ default: HomePage }) };

beforeEach(async () => {
  vi.stubGlobal('fetch', vi.fn(async () => new Response(JSON.stringify({ holder: null, you: false }), { status: 200 })));
  session.user = { username: 'ann', role: 'operator' };
  session.config = /** @type {any} */ ({ cell: { id: 'c', name: 'Demo cell' }, role: 'operator', pages: [{ id: 'home', title: 'Home' }], operation_mode: { topic: '/cell/mode', type: 't', modes: [] } });
  session.offline = false;
  opMode.mode = null;
  opMode.source = null;
  opMode.last = null;
  ros.state = 'connected';
  ros.downSince = null;
  await lastKnown.clear();
});

afterEach(() => {
  lease.reset();
  vi.unstubAllGlobals();
});

describe('Home page', () => {
  it('shows the live mode as live, the lease bar, the user and the cell', async () => {
    opMode.update({ mode: 'running', source: 'ui' });
    render(HomePage, { feature });
    expect(screen.getByTestId('home-mode').textContent).toBe('running');
    expect(screen.getByTestId('home-mode-freshness-age').textContent).toBe('live');
    expect(screen.getByTestId('home-user').textContent).toContain('ann');
    expect(screen.getByTestId('home-cell').textContent).toContain('Demo cell');
    expect(screen.getByTestId('lease-bar')).toBeTruthy();
    expect(await screen.findByRole('button', { name: 'Take control' })).toBeTruthy();
    expect(screen.queryByTestId('last-known')).toBeNull();
  });

  it('ROS down: the last mode stays, marked stale with its age, and the page says why', () => {
    opMode.update({ mode: 'paused', source: 'ui' });
    render(HomePage, { feature });
    opMode.reset();
    ros.state = 'disconnected';
    ros.downSince = Date.now();
    flushSync();
    expect(screen.getByTestId('home-mode').textContent).toBe('paused');
    expect(screen.getByTestId('home-mode-freshness').dataset.stale).toBe('true');
    expect(screen.getByTestId('home-mode-freshness-age').textContent).toMatch(/^stale · /);
    expect(screen.getByTestId('last-known').textContent).toContain('ROS disconnected');
  });

  it('keeps the mode in IndexedDB and shows it on a later offline visit', async () => {
    opMode.update({ mode: 'manual', source: 'pendant' });
    const { unmount } = render(HomePage, { feature });
    await vi.waitFor(async () => expect((await lastKnown.load('home', { user: 'ann' }))?.data.mode.mode).toBe('manual'));
    unmount();

    // A new app run, offline: nothing live, nothing in memory.
    opMode.mode = null;
    opMode.last = null;
    session.offline = true;
    ros.state = 'disconnected';
    render(HomePage, { feature });
    await vi.waitFor(() => expect(screen.getByTestId('home-mode').textContent).toBe('manual'));
    expect(screen.getByTestId('home-mode-freshness').dataset.stale).toBe('true');
    expect(screen.getByTestId('last-known').textContent).toMatch(/Offline.*last known state, from/);
    // Offline: the lease buttons are off.
    expect(/** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Take control' })).disabled).toBe(true);
  });

  it("another user's saved mode is not shown", async () => {
    await lastKnown.save('home', { mode: { mode: 'alarm', source: 'x', at: Date.now() } }, { user: 'someone-else' });
    ros.state = 'disconnected';
    ros.downSince = Date.now();
    render(HomePage, { feature });
    await new Promise((r) => setTimeout(r, 20));
    expect(screen.getByTestId('home-mode').textContent).toBe('—');
  });
});

describe('Home page: the robot of each motion group', () => {
  /** @type {ReturnType<typeof makeFakeFactory>} */
  let f;
  const JOINTS = ['shoulder_pan_joint'];
  /** @param {string[]} groups */
  async function openWith(groups) {
    ros.stop();
    f = makeFakeFactory();
    ros.factory = f.factory;
    ros.url = () => 'ws://test/ros';
    session.config = /** @type {any} */ ({
      cell: { id: 'c', name: 'Cell' }, role: 'admin', pages: [{ id: 'home', title: 'Home' }, { id: 'manual', title: 'Manual motion' }],
      operation_mode: { topic: '/cell/mode', type: 't', modes: [] },
      features: { manual: { groups: groups.map((name) => ({ name, joints: JOINTS })) } },
    });
    render(HomePage, { feature });
    ros.start();
    await flush();
    f.rosList.at(-1)?.emit('connection');
    flushSync();
  }
  afterEach(() => ros.stop());

  it('one group: one "Robot" card on its state topic', async () => {
    await openWith(['arm']);
    const cards = screen.getAllByTestId('home-robot');
    expect(cards.map((c) => c.querySelector('h2')?.textContent)).toEqual(['Robot']);
    expect(f.topicsNamed('/cell/manual/arm/state').map((t) => t.options?.throttle_rate)).toEqual([500]);
    expect(f.topicsNamed('/cell/manual/state')).toEqual([]);
  });

  it('two groups: a card per group, each on its own state topic', async () => {
    await openWith(['left', 'right']);
    const cards = screen.getAllByTestId('home-robot');
    expect(cards.map((c) => c.querySelector('h2')?.textContent)).toEqual(['Robot left', 'Robot right']);
    for (const t of f.topicsNamed('/cell/manual/right/state')) t.deliver({ connected: true, controller: '127.0.2.2', robot_mode: 'RUNNING', safety_mode: 'PROTECTIVE_STOP' });
    flushSync();
    const right = cards[1];
    expect(right.textContent).toContain('connected to 127.0.2.2');
    expect(right.textContent).toContain('Protective stop');
    expect(cards[0].textContent).toContain('no state from the robot driver yet');
  });
});
