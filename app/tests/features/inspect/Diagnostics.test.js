// The Inspect page's Diagnostics view against a fake rosbridge (tests/fakeRos.js), on fake timers so the age of the
// last array can be stepped: subscribed only while shown, the summary, the tree, the filters, the details.
import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, fireEvent, within, cleanup } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import InspectPage from '../../../src/lib/features/inspect/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { clock } from '../../../src/lib/core/clock.svelte.js';
import { makeFakeFactory } from '../../fakeRos.js';

const feature = { id: 'inspect', path: '/inspect', title: 'Inspect', icon: '', load: async () => ({ default: InspectPage }) };
const section = { log_keep_entries: 5000, log_keep_s: 600, can_echo: false };
const TOPIC = '/cell/inspect/diagnostics';

/** A DiagnosticStatus. @param {string} name @param {number} level @param {string} message @param {any} [o] */
const status = (name, level, message, o = {}) => ({ level, name, message, hardware_id: '', values: [], ...o });
const ARRAY = {
  header: { seq: 1, stamp: { secs: 1_780_000_000, nsecs: 0 }, frame_id: '' },
  status: [
    status('vision: camera brightness', 1, 'Image too dark', { hardware_id: 'cam0', values: [{ key: 'mean', value: '31.5' }, { key: 'threshold', value: '40' }] }),
    status('manual: arm controller', 0, 'Running', { hardware_id: 'ur5e-20215' }),
    status('sim_cell: camera Workbench', 3, 'Streaming 15 fps'),
    status('sim_cell: physics', 0, 'OK'),
    status('vision: camera focus', 0, 'Sharp'),
    status('battery', 2, 'Low'),
    status('manual: gripper', 0, 'Open'),
  ],
};

/** @type {ReturnType<typeof makeFakeFactory>} */
let f;

beforeEach(() => {
  vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout', 'setInterval', 'clearInterval', 'Date'] });
  ros.stop();
  f = makeFakeFactory();
  ros.factory = f.factory;
  ros.url = () => 'ws://test/ros';
  session.offline = false;
  session.user = { username: 'operator', role: 'operator' };
  session.config = /** @type {any} */ ({ commands: [], features: { inspect: section } });
  // The clock kept the real Date.now from when it was made: read the faked one.
  vi.spyOn(clock, 'read').mockImplementation(() => Date.now());
});
afterEach(() => {
  cleanup();
  ros.stop();
  vi.useRealTimers();
  vi.restoreAllMocks();
});

/** Let time pass (timers, then promise callbacks), then draw. @param {number} [ms] */
async function settle(ms = 0) {
  await vi.advanceTimersByTimeAsync(ms);
  flushSync();
}
async function connect() {
  ros.start();
  await settle();
  f.rosList.at(-1)?.emit('connection');
  flushSync();
  await settle();
}
/** @param {string} name */
const tab = (name) => screen.getByRole('tab', { name });
/** @param {string} name */
async function showTab(name) {
  await fireEvent.click(tab(name));
  await settle();
}
const live = () => f.topicsNamed(TOPIC).filter((t) => !t.unsubscribed && !t.ros.closed);
/** @param {any} [msg] */
async function deliver(msg = ARRAY) {
  live().at(-1)?.deliver(msg);
  await settle();
}
const rows = () => screen.queryAllByTestId('diag-status');
/** @param {string} name */
const row = (name) => /** @type {HTMLElement} */ (rows().find((r) => r.dataset.name === name));
async function open() {
  render(InspectPage, { feature, section });
  await showTab('Diagnostics');
  await connect();
}

describe('Diagnostics view', () => {
  it('subscribes only while its tab is shown, and unsubscribes when left', async () => {
    render(InspectPage, { feature, section });
    await connect();
    expect(f.topicsNamed(TOPIC)).toHaveLength(0);

    await showTab('Diagnostics');
    expect(tab('Diagnostics').getAttribute('aria-selected')).toBe('true');
    expect(screen.getByTestId('inspect-diagnostics')).toBeTruthy();
    expect(screen.getByRole('tabpanel').getAttribute('aria-labelledby')).toBe(tab('Diagnostics').id);
    const topic = f.topicsNamed(TOPIC)[0];
    expect(f.topicsNamed(TOPIC)).toHaveLength(1);
    expect(topic.type).toBe('diagnostic_msgs/DiagnosticArray');
    expect(topic.options).toMatchObject({ queue_length: 1 });
    expect(topic.unsubscribed).toBe(false);
    // The log's subscription ended with its view.
    expect(f.topicsNamed('/rosout_agg').every((t) => t.unsubscribed)).toBe(true);

    await showTab('Nodes');
    expect(screen.queryByTestId('inspect-diagnostics')).toBeNull();
    expect(topic.unsubscribed).toBe(true);
    expect(live()).toHaveLength(0);

    await showTab('Diagnostics');
    expect(live()).toHaveLength(1);
  });

  it('says nothing was received yet, then shows the summary and the age of the last array', async () => {
    render(InspectPage, { feature, section });
    await showTab('Diagnostics');
    expect(screen.getByTestId('diag-empty').textContent).toContain('No diagnostics received yet');
    await connect();
    expect(screen.getByTestId('diag-empty').textContent?.trim()).toBe('No diagnostics received yet: drivers publish them on /diagnostics.');
    expect(screen.queryByTestId('diag-age')).toBeNull();

    await deliver();
    expect(screen.queryByTestId('diag-empty')).toBeNull();
    expect(screen.getByTestId('diag-summary').textContent).toContain('4 OK · 1 warning · 1 error · 1 stale');
    expect(screen.getByTestId('diag-age').textContent).toContain('updated just now');

    await settle(2000);
    expect(screen.getByTestId('diag-age').textContent).toContain('updated 2 s ago');
    await settle(1000);
    expect(screen.getByTestId('diag-age').textContent).toContain('no update for 3 s');
    expect(screen.getByTestId('diag-age').classList.contains('stale')).toBe(true);

    // The next array: fresh again, and its statuses replace the last ones.
    await deliver({ ...ARRAY, status: [status('vision: camera brightness', 0, 'OK')] });
    expect(screen.getByTestId('diag-age').textContent).toContain('updated just now');
    expect(screen.getByTestId('diag-summary').textContent).toContain('1 OK · 0 warnings · 0 errors · 0 stale');
    expect(rows().map((r) => r.dataset.name)).toEqual(['vision: camera brightness']);

    // An empty array: nothing reported on /diagnostics yet.
    await deliver({ ...ARRAY, status: [] });
    expect(screen.getByTestId('diag-empty').textContent).toContain('No diagnostics received yet');
    expect(screen.getByTestId('diag-summary').textContent).toContain('0 OK · 0 warnings · 0 errors · 0 stale');
  });

  it('rows carry their level as data and as text; the stale level reads STALE', async () => {
    await open();
    await deliver();
    expect(rows()).toHaveLength(7);
    const levels = Object.fromEntries(rows().map((r) => [r.dataset.name, r.dataset.level]));
    expect(levels).toEqual({
      'vision: camera brightness': 'warn', 'manual: arm controller': 'ok', 'sim_cell: camera Workbench': 'stale',
      'sim_cell: physics': 'ok', 'vision: camera focus': 'ok', battery: 'error', 'manual: gripper': 'ok',
    });

    const stale = row('sim_cell: camera Workbench');
    expect(within(stale).getByTestId('diag-level').textContent).toBe('STALE');
    // The name without its group, and the last message it had.
    expect(stale.textContent).toContain('camera Workbench');
    expect(within(stale).getByTestId('diag-message').textContent).toContain('Streaming 15 fps');
    expect(within(stale).getByTestId('diag-message').textContent).toContain('last reported');
    expect(within(row('vision: camera brightness')).getByTestId('diag-level').textContent).toBe('WARN');
    expect(within(row('battery')).getByTestId('diag-level').textContent).toBe('ERROR');
    expect(within(row('manual: gripper')).getByTestId('diag-level').textContent).toBe('OK');
    expect(within(row('manual: gripper')).getByTestId('diag-message').textContent?.trim()).toBe('Open');
  });

  it('groups by component, worst group first, worst status first; groups fold', async () => {
    await open();
    await deliver();
    const groups = screen.getAllByTestId('diag-group');
    expect(groups.map((g) => [g.dataset.group, g.dataset.level])).toEqual([
      ['other', 'error'], ['sim_cell', 'stale'], ['vision', 'warn'], ['manual', 'ok'],
    ]);
    expect(within(groups[1]).getByTestId('diag-group-level').textContent).toBe('STALE');
    expect(within(groups[2]).getAllByTestId('diag-status').map((r) => r.dataset.name)).toEqual(['vision: camera brightness', 'vision: camera focus']);
    expect(within(groups[1]).getAllByTestId('diag-status').map((r) => r.dataset.name)).toEqual(['sim_cell: camera Workbench', 'sim_cell: physics']);
    expect(within(groups[0]).getAllByTestId('diag-status').map((r) => r.dataset.name)).toEqual(['battery']);

    const vision = screen.getByRole('button', { name: 'Group vision' });
    expect(vision.getAttribute('aria-expanded')).toBe('true');
    await fireEvent.click(vision);
    expect(vision.getAttribute('aria-expanded')).toBe('false');
    expect(within(groups[2]).queryAllByTestId('diag-status')).toHaveLength(0);
    expect(rows()).toHaveLength(5);
    // Folded stays folded when the next array comes.
    await deliver();
    expect(screen.getByRole('button', { name: 'Group vision' }).getAttribute('aria-expanded')).toBe('false');
    await fireEvent.click(screen.getByRole('button', { name: 'Group vision' }));
    expect(rows()).toHaveLength(7);
  });

  it('Problems only hides the OK statuses; the text filter narrows further', async () => {
    await open();
    await deliver();
    const show = /** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name: 'Show' }));
    expect([...show.options].map((o) => o.textContent)).toEqual(['All', 'Problems only']);
    expect(show.value).toBe('all');

    await fireEvent.change(show, { target: { value: 'problems' } });
    expect(rows().map((r) => r.dataset.name)).toEqual(['battery', 'sim_cell: camera Workbench', 'vision: camera brightness']);
    expect(rows().every((r) => r.dataset.level !== 'ok')).toBe(true);
    expect(screen.queryByRole('button', { name: 'Group manual' })).toBeNull();
    expect(screen.getByTestId('diag-count').textContent).toBe('3 of 7 statuses shown');
    // The summary still counts everything.
    expect(screen.getByTestId('diag-summary').textContent).toContain('4 OK · 1 warning · 1 error · 1 stale');

    const text = screen.getByRole('searchbox', { name: 'Filter diagnostics' });
    await fireEvent.input(text, { target: { value: 'camera' } });
    expect(rows().map((r) => r.dataset.name)).toEqual(['sim_cell: camera Workbench', 'vision: camera brightness']);
    await fireEvent.change(show, { target: { value: 'all' } });
    expect(rows().map((r) => r.dataset.name)).toEqual(['sim_cell: camera Workbench', 'vision: camera brightness', 'vision: camera focus']);
    await fireEvent.input(text, { target: { value: 'nothing like it' } });
    expect(screen.getByTestId('diag-empty').textContent?.trim()).toBe('No diagnostics match the filters.');
  });

  it('a row opens to its hardware id and values', async () => {
    await open();
    await deliver();
    const btn = screen.getByRole('button', { name: 'Details of vision: camera brightness' });
    expect(btn.getAttribute('aria-expanded')).toBe('false');
    expect(screen.queryByTestId('diag-details')).toBeNull();

    await fireEvent.click(btn);
    expect(btn.getAttribute('aria-expanded')).toBe('true');
    const details = within(row('vision: camera brightness')).getByTestId('diag-details');
    expect(btn.getAttribute('aria-controls')).toBe(details.id);
    expect(details.textContent).toContain('Hardware ID: cam0');
    expect(within(details).getAllByRole('term').map((t) => t.textContent)).toEqual(['mean', 'threshold']);
    expect(within(details).getAllByRole('definition').map((t) => t.textContent)).toEqual(['31.5', '40']);

    // Still open after the next array; a status without values says so.
    await deliver();
    expect(within(row('vision: camera brightness')).getByTestId('diag-details')).toBeTruthy();
    await fireEvent.click(screen.getByRole('button', { name: 'Details of manual: arm controller' }));
    const arm = within(row('manual: arm controller')).getByTestId('diag-details');
    expect(arm.textContent).toContain('ur5e-20215');
    expect(arm.textContent).toContain('No values.');

    await fireEvent.click(btn);
    expect(within(row('vision: camera brightness')).queryByTestId('diag-details')).toBeNull();
  });

  it('when ROS drops: the not-live notice, the last statuses kept, and re-subscribed on reconnect', async () => {
    await open();
    await deliver();
    expect(screen.queryByTestId('inspect-not-live')).toBeNull();
    f.rosList.at(-1)?.emit('close');
    await settle();
    expect(screen.getByTestId('inspect-not-live').textContent).toContain('the diagnostics shown may be out of date');
    expect(rows()).toHaveLength(7);
    await settle(5000);
    expect(screen.getByTestId('diag-age').textContent).toContain('no update for 5 s');

    ros.retryNow();
    await settle();
    f.rosList.at(-1)?.emit('connection');
    flushSync();
    await settle();
    expect(screen.queryByTestId('inspect-not-live')).toBeNull();
    // The latched array comes again on the new socket.
    expect(live()).toHaveLength(1);
    await deliver({ ...ARRAY, status: [status('manual: arm controller', 0, 'Running')] });
    expect(rows().map((r) => r.dataset.name)).toEqual(['manual: arm controller']);
    expect(screen.getByTestId('diag-age').textContent).toContain('updated just now');
  });
});
