// The Inspect page (the ROS log) against a fake rosbridge (tests/fakeRos.js): history + live merge, filters,
// pause, export, reconnect, a log storm.
import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, fireEvent, within, cleanup } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import InspectPage from '../../../src/lib/features/inspect/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { formatClock } from '../../../src/lib/features/inspect/logic.js';
import { makeFakeFactory, flush } from '../../fakeRos.js';

const feature = { id: 'inspect', path: '/inspect', title: 'Inspect', icon: '', load: async () => ({ default: InspectPage }) };
const section = { log_keep_entries: 5000, log_keep_s: 600 };
const SECS = Math.floor(Date.UTC(2026, 10, 26, 14, 0, 0) / 1000);

/** A RosLogEntry i ms after SECS. @param {number} i @param {any} [o] */
const hist = (i, o = {}) => ({
  stamp: { secs: SECS, nsecs: i * 1e6 }, level: 2, node: '/process_node', msg: `entry ${i}`, file: 'process.py', function: 'run', line: 10, ...o,
});
/** The same as a rosgraph_msgs/Log. @param {number} i @param {any} [o] */
const log = (i, o = {}) => {
  const { stamp, node, ...rest } = hist(i, o);
  return { header: { seq: i, stamp, frame_id: '' }, name: o.name ?? node, topics: [], ...rest };
};

/** @type {ReturnType<typeof makeFakeFactory>} */
let f;

beforeEach(() => {
  ros.stop();
  f = makeFakeFactory();
  ros.factory = f.factory;
  ros.url = () => 'ws://test/ros';
  session.offline = false;
  session.user = { username: 'admin', role: 'admin' };
  session.config = /** @type {any} */ ({ commands: [], features: { inspect: section } });
});
afterEach(() => {
  cleanup();
  ros.stop();
  vi.unstubAllGlobals();
  vi.restoreAllMocks();
});

async function connect() {
  ros.start();
  await flush();
  f.rosList.at(-1)?.emit('connection');
  flushSync();
  await flush();
}
const historyCalls = () => f.calls.filter((c) => c.name === '/cell/inspect/log');
const liveTopic = () => f.topicsNamed('/rosout_agg').find((t) => !t.unsubscribed && !t.ros.closed);
const rowMsgs = () => screen.queryAllByTestId('log-entry').map((li) => li.querySelector('.msg')?.textContent);
/** @param {any} answer */
const answer = (answer) => historyCalls().at(-1)?.ok({ matched: answer.entries.length, dropped: 0, kept_s: 30, ...answer });

describe('Inspect page', () => {
  it('loads the history on connect, keeps the live entries that came meanwhile, no duplicates, newest first', async () => {
    render(InspectPage, { feature, section });
    expect(screen.getByTestId('inspect-keep').textContent).toBe('The robot PC keeps the last 10 min of the ROS log, at most 5000 entries; this page keeps the newest 2000.');
    expect(screen.getByTestId('inspect-history').textContent).toBe('History: loaded once connected to ROS');
    expect(screen.getByTestId('log-empty').textContent).toContain('Waiting for the connection to ROS');
    await connect();

    const call = historyCalls()[0];
    expect(call.type).toBe('cell_msgs/LogQuery');
    expect(call.args).toEqual({ min_level: 0, node: '', text: '', max_entries: 2000 });
    const topic = liveTopic();
    expect(topic?.type).toBe('rosgraph_msgs/Log');
    expect(topic?.options).toMatchObject({ queue_length: 100 });
    expect(topic?.options.throttle_rate ?? 0).toBe(0);

    // While the call is in flight: one entry the history also has, and a newer one.
    topic?.deliver(log(2));
    topic?.deliver(log(3, { level: 4, name: '/driver', msg: 'Slow cycle\nsecond line', file: 'driver.cpp', line: 77 }));
    await vi.waitFor(() => expect(rowMsgs()).toEqual(['Slow cycle\nsecond line', 'entry 2']));
    call.ok({ entries: [hist(0), hist(1, { level: 8 }), hist(2)], matched: 4800, dropped: 12, kept_s: 598 });
    await vi.waitFor(() => expect(rowMsgs()).toEqual(['Slow cycle\nsecond line', 'entry 2', 'entry 1', 'entry 0']));
    expect(screen.getByTestId('inspect-history').textContent).toBe('History: the last 10 min (4800 entries kept on the robot PC, 12 dropped) · the newest 3 loaded');
    expect(screen.getByTestId('log-count').textContent).toBe('4 entries');

    const list = screen.getByRole('list', { name: 'ROS log' });
    const rows = within(list).getAllByTestId('log-entry');
    expect(rows[0].dataset.level).toBe('warn');
    expect(rows[0].dataset.node).toBe('/driver');
    expect(rows[0].textContent).toContain('WARN');
    expect(rows[0].textContent).toContain(formatClock(SECS * 1000 + 3));
    expect(rows[0].textContent).toContain('driver.cpp:77');
    expect(rows[2].dataset.level).toBe('error');
    expect(within(rows[2]).getByText('ERROR')).toBeTruthy();
    expect(screen.queryByTestId('inspect-not-live')).toBeNull();
  });

  it('filters by level, node and text; the node list has the nodes seen', async () => {
    render(InspectPage, { feature, section });
    await connect();
    answer({ entries: [
      hist(0, { level: 1, node: '/driver', msg: 'rtde tick' }),
      hist(1, { msg: 'Move to part 2' }),
      hist(2, { level: 4, msg: 'Slow cycle' }),
      hist(3, { level: 8, node: '/driver', msg: 'Protective stop', file: 'ur_driver.cpp' }),
    ] });
    await vi.waitFor(() => expect(rowMsgs().length).toBe(4));

    const level = /** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name: 'Minimum level' }));
    expect(level.value).toBe('debug');
    expect([...level.options].map((o) => o.textContent)).toEqual(['Debug', 'Info', 'Warn', 'Error', 'Fatal']);
    const node = /** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name: 'Node' }));
    expect([...node.options].map((o) => o.textContent)).toEqual(['All nodes', '/driver', '/process_node']);

    await fireEvent.change(level, { target: { value: 'warn' } });
    expect(rowMsgs()).toEqual(['Protective stop', 'Slow cycle']);
    expect(screen.getByTestId('log-count').textContent).toBe('2 entries (filtered from 4)');
    await fireEvent.change(level, { target: { value: 'debug' } });
    await fireEvent.change(node, { target: { value: '/driver' } });
    expect(rowMsgs()).toEqual(['Protective stop', 'rtde tick']);
    await fireEvent.input(screen.getByRole('searchbox', { name: 'Search the log' }), { target: { value: 'UR_DRIVER' } });
    expect(rowMsgs()).toEqual(['Protective stop']);
    await fireEvent.input(screen.getByRole('searchbox', { name: 'Search the log' }), { target: { value: 'nothing like it' } });
    expect(rowMsgs()).toEqual([]);
    expect(screen.getByTestId('log-empty').textContent).toBe('No entries match the filters.');
    expect(/** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Export' })).disabled).toBe(true);
  });

  it('Pause counts new entries without showing them; Resume shows them', async () => {
    render(InspectPage, { feature, section });
    await connect();
    answer({ entries: [hist(0), hist(1)] });
    await vi.waitFor(() => expect(rowMsgs().length).toBe(2));
    const pause = screen.getByRole('button', { name: 'Pause' });
    expect(pause.getAttribute('aria-pressed')).toBe('false');
    await fireEvent.click(pause);
    expect(pause.getAttribute('aria-pressed')).toBe('true');
    expect(screen.getByTestId('log-paused').textContent).toContain('0 new entries');

    const topic = liveTopic();
    for (const i of [1, 2, 3]) topic?.deliver(log(i)); // 1 is not new
    await vi.waitFor(() => expect(screen.getByTestId('log-new-count').textContent).toBe('2 new entries'));
    expect(rowMsgs()).toEqual(['entry 1', 'entry 0']);

    await fireEvent.click(screen.getByRole('button', { name: 'Resume' }));
    expect(pause.getAttribute('aria-pressed')).toBe('false');
    expect(screen.queryByTestId('log-paused')).toBeNull();
    expect(rowMsgs()).toEqual(['entry 3', 'entry 2', 'entry 1', 'entry 0']);
  });

  it('Export downloads the filtered entries as a text file', async () => {
    /** @type {Blob | null} */
    let blob = null;
    const createObjectURL = vi.fn((/** @type {Blob} */ b) => ((blob = b), 'blob:test/1'));
    vi.stubGlobal('URL', Object.assign(class extends URL {}, { createObjectURL, revokeObjectURL: vi.fn() }));
    /** @type {{ href: string, download: string }[]} */
    const clicked = [];
    vi.spyOn(HTMLAnchorElement.prototype, 'click').mockImplementation(/** @this {HTMLAnchorElement} */ function () {
      clicked.push({ href: this.getAttribute('href') ?? '', download: this.download });
    });
    render(InspectPage, { feature, section });
    await connect();
    answer({ entries: [hist(0, { msg: 'a' }), hist(1, { level: 8, msg: 'b', node: '/driver', file: 'd.cpp', line: 5 })] });
    await vi.waitFor(() => expect(rowMsgs().length).toBe(2));
    await fireEvent.change(screen.getByRole('combobox', { name: 'Minimum level' }), { target: { value: 'error' } });
    await fireEvent.click(screen.getByRole('button', { name: 'Export' }));
    expect(clicked).toHaveLength(1);
    expect(clicked[0].href).toBe('blob:test/1');
    expect(clicked[0].download).toMatch(/^ros-log-\d{8}T\d{6}Z\.log$/);
    const text = await /** @type {Blob} */ (/** @type {unknown} */ (blob)).text();
    expect(text).toBe('2026-11-26T14:00:00.001Z ERROR /driver b d.cpp:5\n');
  });

  it('says when ROS is disconnected, and loads the history again after the reconnect', async () => {
    render(InspectPage, { feature, section });
    await connect();
    answer({ entries: [hist(0)] });
    await vi.waitFor(() => expect(rowMsgs().length).toBe(1));
    f.rosList.at(-1)?.emit('close');
    flushSync();
    expect(screen.getByTestId('inspect-not-live').textContent).toContain('ROS disconnected');
    expect(rowMsgs()).toEqual(['entry 0']); // what was seen stays

    ros.retryNow();
    await flush();
    f.rosList.at(-1)?.emit('connection');
    flushSync();
    await flush();
    expect(historyCalls()).toHaveLength(2);
    expect(screen.queryByTestId('inspect-not-live')).toBeNull();
    answer({ entries: [hist(0), hist(5, { msg: 'while away' })] });
    await vi.waitFor(() => expect(rowMsgs()).toEqual(['while away', 'entry 0']));
    // Live entries still arrive on the new socket.
    liveTopic()?.deliver(log(6));
    await vi.waitFor(() => expect(rowMsgs()[0]).toBe('entry 6'));
  });

  it('a history call cut by a dropped link is no error: the notice says disconnected, the reconnect asks again', async () => {
    render(InspectPage, { feature, section });
    await connect();
    expect(historyCalls()).toHaveLength(1);
    f.rosList.at(-1)?.emit('close');
    flushSync();
    await flush();
    expect(screen.queryByRole('alert')).toBeNull();
    expect(screen.getByTestId('inspect-history').textContent).toBe('History: loaded once connected to ROS');
    expect(screen.getByTestId('inspect-not-live').textContent).toContain('ROS disconnected');
  });

  it('a failed history call says why and can be tried again; the live log goes on', async () => {
    render(InspectPage, { feature, section });
    await connect();
    historyCalls()[0].fail('service [/cell/inspect/log] unavailable');
    await vi.waitFor(() => expect(screen.getByRole('alert').textContent).toContain('Could not load the log history: service [/cell/inspect/log] unavailable'));
    liveTopic()?.deliver(log(1));
    await vi.waitFor(() => expect(rowMsgs()).toEqual(['entry 1']));
    await fireEvent.click(screen.getByRole('button', { name: 'Load the history again' }));
    expect(historyCalls()).toHaveLength(2);
    answer({ entries: [hist(0)] });
    await vi.waitFor(() => expect(rowMsgs()).toEqual(['entry 1', 'entry 0']));
    expect(screen.queryByRole('alert')).toBeNull();
  });

  it('a log storm: applied in batches, 2000 kept, the newest 300 drawn', async () => {
    render(InspectPage, { feature, section });
    await connect();
    answer({ entries: [] });
    const topic = liveTopic();
    for (let i = 0; i < 5000; i++) topic?.deliver(log(i));
    // Not applied at once: the page draws at most every 200 ms.
    expect(rowMsgs().length).toBe(0);
    await vi.waitFor(() => expect(screen.getByTestId('log-count').textContent).toBe('Showing the newest 300 of 2000 entries'));
    const msgs = rowMsgs();
    expect(msgs.length).toBe(300);
    expect(msgs[0]).toBe('entry 4999');
    expect(msgs[299]).toBe('entry 4700');
  });
});
