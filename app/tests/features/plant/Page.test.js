// The Plant page against a fake BFF (fetch) and a fake Server-Sent Events feed (EventSource).
import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, within, cleanup } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import PlantPage from '../../../src/lib/features/plant/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { lastKnown } from '../../../src/lib/core/lastKnown.js';

const feature = { id: 'plant', path: '/plant', title: 'Plant', icon: '', load: async () => ({ default: PlantPage }) };

/** @param {any} [o] */
const cell = (o = {}) => ({
  id: `plant-a/${o.node ?? 'demo-ur5'}`, group: 'plant-a', node: 'demo-ur5', name: 'Demo UR5 cell', url: 'http://10.0.0.5:8080/',
  online: true, since: Date.now() - 5 * 60_000, ros: true, mode: 'running', safety: 'normal', alarms: 0, alarm: 'no active alarm',
  severity: -1, process: 'running', operation: 'Pick part', cycles: 12, last_cycle_s: 8.25,
  robots: [{ group: 'ur5', connected: true, mode: 'RUNNING' }],
  modules: [{ name: 'vision', state: 'active' }, { name: 'gripper', state: 'active' }, { name: 'conveyor', state: 'inactive' }],
  updated: Date.now(), ...o,
});
const broker = { state: 'connected', since: Date.now() - 60_000, error: '' };

class FakeEventSource {
  /** @type {FakeEventSource[]} */
  static all = [];
  /** @param {string} url */
  constructor(url) {
    this.url = url;
    this.readyState = 0;
    this.closed = false;
    /** @type {Record<string, ((e: any) => void)[]>} */
    this.listeners = {};
    FakeEventSource.all.push(this);
  }
  /** @param {string} type @param {(e: any) => void} fn */
  addEventListener(type, fn) {
    (this.listeners[type] ??= []).push(fn);
  }
  removeEventListener() {}
  close() {
    this.closed = true;
    this.readyState = 2;
  }
  /** @param {string} type @param {any} [e] */
  emit(type, e = {}) {
    if (type === 'open') this.readyState = 1;
    for (const fn of this.listeners[type] ?? []) fn(e);
    flushSync();
  }
  /** @param {any} data */
  cells(data) {
    this.emit('cells', { data: JSON.stringify(data) });
  }
  static get open() {
    return FakeEventSource.all.filter((s) => !s.closed);
  }
}

/** @type {any} */
let answer;
let status = 200;
/** @type {string[]} */
let calls;

beforeEach(async () => {
  session.user = { username: 'lead', role: 'lead' };
  session.offline = false;
  await lastKnown.clear();
  FakeEventSource.all = [];
  calls = [];
  status = 200;
  answer = { broker, cells: [] };
  vi.stubGlobal('EventSource', FakeEventSource);
  vi.stubGlobal('fetch', vi.fn(async (/** @type {string} */ url) => {
    calls.push(url);
    if (url === '/api/plant/cells') return new Response(JSON.stringify(status === 200 ? answer : { error: 'not for you' }), { status });
    return new Response(JSON.stringify({ error: 'no route' }), { status: 404 });
  }));
});
afterEach(() => {
  cleanup();
  vi.unstubAllGlobals();
  vi.useRealTimers();
});

const cards = () => screen.getAllByRole('article');

describe('Plant page', () => {
  it('lists the cells, alarms first, then offline, then the rest by name, with their details and links', async () => {
    answer = {
      broker,
      cells: [
        cell({ node: 'zeta', name: 'Zeta cell' }),
        cell({ node: 'weld-2', name: 'Welding 2', online: false, ros: false, url: '' }),
        cell({ node: 'demo-ur5' }),
        cell({ node: 'pack-1', name: '', alarms: 0, severity: 2, alarm: 'Gripper lost the part', safety: 'protective stop' }),
      ],
    };
    render(PlantPage, { feature });
    await vi.waitFor(() => expect(cards().length).toBe(4));
    expect(cards().map((a) => a.getAttribute('data-testid'))).toEqual(['plant-cell-pack-1', 'plant-cell-weld-2', 'plant-cell-demo-ur5', 'plant-cell-zeta']);
    expect(cards().map((a) => a.getAttribute('data-status'))).toEqual(['alarm', 'offline', 'ok', 'ok']);
    expect(calls).toEqual(['/api/plant/cells']);
    expect(FakeEventSource.all.map((s) => s.url)).toEqual(['/api/plant/events']);

    // Accessible names: the cell's name, its node when it has none.
    const demo = screen.getByRole('article', { name: 'Demo UR5 cell' });
    const pack = screen.getByRole('article', { name: 'pack-1' });
    const link = within(demo).getByRole('link', { name: 'Open Demo UR5 cell' });
    expect(link.getAttribute('href')).toBe('http://10.0.0.5:8080/');
    expect(link.getAttribute('target')).toBe('_blank');
    expect(link.getAttribute('rel')).toBe('noopener');
    expect(within(pack).getByRole('link', { name: 'Open pack-1' })).toBeTruthy();
    // No url: no link.
    expect(within(screen.getByRole('article', { name: 'Welding 2' })).queryByRole('link')).toBeNull();

    expect(demo.textContent).toMatch(/Online since \d\d:\d\d \(5 min\)/);
    expect(demo.textContent).toContain('ur5: connected, RUNNING');
    expect(demo.textContent).toContain('2 of 3 modules active');
    expect(demo.textContent).toContain('running · Pick part');
    expect(demo.textContent).toContain('8.3 s');
    expect(demo.textContent).not.toContain('ROS link down');
    const alarm = within(pack).getByTestId('plant-cell-alarm');
    expect(alarm.textContent).toBe('Error alarm: Gripper lost the part');
    expect(alarm.dataset.active).toBe('true');
    expect(within(demo).getByTestId('plant-cell-alarm').dataset.active).toBe('false');
    expect(within(pack).getByTestId('plant-cell-safety').textContent).toBe('Protective stop');
    const weld = screen.getByTestId('plant-cell-weld-2');
    expect(weld.textContent).toMatch(/Offline since \d\d:\d\d \(5 min\)/);
    expect(weld.textContent).toContain('ROS link down');

    expect(screen.getByTestId('plant-broker').textContent).toBe('Broker connected');
    expect(screen.getByTestId('plant-count').textContent).toBe('4 cells, 1 with alarms, 1 offline');
    expect(screen.queryByTestId('plant-stale')).toBeNull();
    expect(screen.getByTestId('plant-cells').dataset.stale).toBe('false');
  });

  it('follows the events: a new alarm moves the cell to the top', async () => {
    answer = { broker, cells: [cell({ node: 'a', name: 'Alpha' }), cell({ node: 'b', name: 'Bravo' })] };
    render(PlantPage, { feature });
    await vi.waitFor(() => expect(cards().length).toBe(2));
    expect(cards().map((a) => a.dataset.testid)).toEqual(['plant-cell-a', 'plant-cell-b']);
    const es = FakeEventSource.open[0];
    es.emit('open');
    es.cells({ broker, cells: [cell({ node: 'a', name: 'Alpha' }), cell({ node: 'b', name: 'Bravo', alarms: 1, alarm: 'Door open' })] });
    expect(cards().map((a) => a.dataset.testid)).toEqual(['plant-cell-b', 'plant-cell-a']);
    expect(screen.getByTestId('plant-cell-b').dataset.status).toBe('alarm');
    expect(within(screen.getByTestId('plant-cell-b')).getByTestId('plant-cell-alarm').textContent).toBe('1 active alarm: Door open');
    expect(screen.getByTestId('plant-count').textContent).toBe('2 cells, 1 with alarms');
  });

  it('on a feed error keeps the last list marked stale and says it reconnects; the next event clears it', async () => {
    answer = { broker, cells: [cell()] };
    render(PlantPage, { feature });
    await vi.waitFor(() => expect(cards().length).toBe(1));
    const es = FakeEventSource.open[0];
    es.emit('open');
    es.emit('error'); // readyState CONNECTING: EventSource retries by itself
    expect(screen.getByTestId('plant-stale').textContent).toMatch(/Reconnecting.*marked stale/);
    expect(screen.getByTestId('plant-cells').dataset.stale).toBe('true');
    expect(screen.getByRole('article', { name: 'Demo UR5 cell' })).toBeTruthy();
    expect(es.closed).toBe(false); // not closed: the browser retries it
    expect(FakeEventSource.all.length).toBe(1);

    es.emit('open');
    es.cells({ broker, cells: [cell({ cycles: 13 })] });
    expect(screen.queryByTestId('plant-stale')).toBeNull();
    expect(screen.getByTestId('plant-cells').dataset.stale).toBe('false');
  });

  it('a feed closed for good is reopened after a while, asking the API first', async () => {
    vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout'] });
    answer = { broker, cells: [cell()] };
    render(PlantPage, { feature });
    await vi.waitFor(() => expect(cards().length).toBe(1));
    const es = FakeEventSource.open[0];
    es.readyState = 2;
    es.emit('error');
    expect(es.closed).toBe(true);
    expect(screen.getByTestId('plant-stale')).toBeTruthy();
    await vi.advanceTimersByTimeAsync(5000);
    await vi.waitFor(() => expect(FakeEventSource.open.length).toBe(1));
    expect(FakeEventSource.all.length).toBe(2);
    expect(calls).toEqual(['/api/plant/cells', '/api/plant/cells']);
  });

  it('closes the feed when the app is hidden and reopens it when visible; closes it when the page goes', async () => {
    answer = { broker, cells: [cell()] };
    let hidden = false;
    const spy = vi.spyOn(document, 'visibilityState', 'get').mockImplementation(() => (hidden ? 'hidden' : 'visible'));
    const { unmount } = render(PlantPage, { feature });
    await vi.waitFor(() => expect(cards().length).toBe(1));
    const first = FakeEventSource.open[0];
    hidden = true;
    document.dispatchEvent(new Event('visibilitychange'));
    flushSync();
    expect(first.closed).toBe(true);
    expect(FakeEventSource.open.length).toBe(0);
    hidden = false;
    document.dispatchEvent(new Event('visibilitychange'));
    flushSync();
    expect(FakeEventSource.open.length).toBe(1);
    const second = FakeEventSource.open[0];
    expect(second).not.toBe(first);
    unmount();
    expect(second.closed).toBe(true);
    spy.mockRestore();
  });

  it('empty plant: says no cell has reported yet, with the broker state', async () => {
    answer = { broker: { state: 'down', since: Date.now() - 1000, error: 'connect ECONNREFUSED 10.0.0.1:1883' }, cells: [] };
    render(PlantPage, { feature });
    const empty = await screen.findByTestId('plant-empty');
    expect(empty.textContent).toBe('No cell has reported yet (Broker unreachable: connect ECONNREFUSED 10.0.0.1:1883).');
    expect(screen.getByTestId('plant-broker').dataset.tone).toBe('danger');
    expect(screen.queryAllByRole('article')).toEqual([]);
  });

  it('403: access denied and no feed', async () => {
    status = 403;
    render(PlantPage, { feature });
    expect(await screen.findByTestId('access-denied')).toBeTruthy();
    expect(FakeEventSource.open.length).toBe(0);
  });

  it('offline: shows the last known list, marked stale, with its age', async () => {
    await lastKnown.save('plant', { broker, cells: [cell({ node: 'old', name: 'Old cell' })] }, { user: 'lead', savedAt: Date.now() - 3 * 60_000 });
    vi.stubGlobal('fetch', vi.fn(async () => { throw new TypeError('Failed to fetch'); }));
    render(PlantPage, { feature });
    await vi.waitFor(() => expect(screen.getByRole('article', { name: 'Old cell' })).toBeTruthy());
    expect(screen.getByTestId('last-known').textContent).toMatch(/Offline.*from 3 min ago/);
    expect(screen.getByTestId('plant-cells').dataset.stale).toBe('true');
    expect(session.offline).toBe(true);
  });
});
