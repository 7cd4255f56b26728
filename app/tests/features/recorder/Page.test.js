// The Recordings page against a fake BFF (fetch) and a fake rosbridge (tests/fakeRos.js).
import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, fireEvent, within, cleanup } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import RecorderPage from '../../../src/lib/features/recorder/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { formatDate } from '../../../src/lib/features/recorder/logic.js';
import { makeFakeFactory, flush } from '../../fakeRos.js';

const M = '\u2212';
const feature = { id: 'recorder', path: '/recorder', title: 'Recordings', icon: '', load: async () => ({ default: RecorderPage }) };
const section = { before_s: 120, after_s: 10 };
const AT = Date.UTC(2026, 10, 26, 14, 5, 12, 123);
const NEW = '20261126T140512.123Z-alarm-robot-protective-stop-robot-protective-stop.mcap';
const OLD = '20261125T090000.000Z-saved-by-hand.mcap';
const rec = (/** @type {string} */ name, /** @type {number} */ at, /** @type {any} */ o = {}) => ({
  name, at_ms: at, reason: 'alarm robot.protective_stop: Robot protective stop', size: 2048, duration_s: 130, messages: 10, alarms: ['robot.protective_stop'], ...o,
});
const detailOf = (/** @type {any} */ r) => ({
  ...r, start_ms: r.at_ms - 120000, end_ms: r.at_ms + 10000,
  topics: [{ topic: '/joint_states', type: 'sensor_msgs/JointState', count: 6500 }, { topic: '/cell/mode', type: 'cell_msgs/OperationMode', count: 13 }],
  timeline: { lanes: [
    { id: 'alarms', title: 'Alarms', changes: [{ t_ms: r.at_ms - 120000, text: '' }, { t_ms: r.at_ms - 100, text: 'robot.protective_stop: Robot protective stop' }] },
    { id: 'process', title: 'Process', changes: [{ t_ms: r.at_ms - 120000, text: 'running · Move to part 2 (approach)' }, { t_ms: r.at_ms - 3200, text: 'error · Move failed' }] },
    { id: 'mode', title: 'Operation mode', changes: [{ t_ms: r.at_ms - 120000, text: 'running' }, { t_ms: r.at_ms - 100, text: 'alarm' }] },
  ] },
});

/** @type {{ method: string, url: string }[]} */
let calls;
/** @type {any[]} */
let list;
let canDelete = true;
/** @type {ReturnType<typeof makeFakeFactory>} */
let f;
const json = (/** @type {any} */ data, status = 200) => new Response(JSON.stringify(data), { status });

beforeEach(() => {
  ros.stop();
  f = makeFakeFactory();
  ros.factory = f.factory;
  ros.url = () => 'ws://test/ros';
  session.offline = false;
  session.user = { username: 'admin', role: 'admin' };
  session.config = /** @type {any} */ ({ commands: ['recorder'], features: { recorder: section } });
  calls = [];
  canDelete = true;
  list = [rec(NEW, AT), rec(OLD, AT - 86400e3, { reason: 'saved by hand', alarms: [] })];
  vi.stubGlobal('fetch', vi.fn(async (/** @type {string} */ url, /** @type {RequestInit} */ init) => {
    const method = init?.method ?? 'GET';
    calls.push({ method, url });
    if (method === 'GET' && url === '/api/recorder/recordings') return json({ recordings: list, can_delete: canDelete });
    const m = /^\/api\/recorder\/recordings\/([^/]+)$/.exec(url);
    const r = m && list.find((x) => x.name === decodeURIComponent(m[1]));
    if (r && method === 'GET') return json(detailOf(r));
    if (r && method === 'DELETE') {
      list = list.filter((x) => x !== r);
      return json({ deleted: r.name });
    }
    return json({ error: `no route ${method} ${url}` }, 404);
  }));
});
afterEach(() => {
  cleanup();
  ros.stop();
  vi.unstubAllGlobals();
});

async function connect() {
  ros.start();
  await flush();
  f.rosList.at(-1)?.emit('connection');
  flushSync();
}

describe('Recordings page', () => {
  it('lists the recordings and shows the newest one\'s timeline, events and topics', async () => {
    render(RecorderPage, { feature, section });
    expect(screen.getByTestId('recorder-window').textContent).toContain('Each error alarm saves the 120 s before it and the 10 s after it.');
    const rows = await screen.findAllByTestId('recording');
    expect(rows.map((r) => r.getAttribute('data-name'))).toEqual([NEW, OLD]);
    const when = formatDate(AT);
    expect(within(rows[0]).getByText('alarm robot.protective_stop: Robot protective stop')).toBeTruthy();
    const download = screen.getByRole('link', { name: `Download recording of ${when}` });
    expect(download.getAttribute('href')).toBe(`/api/recorder/recordings/${NEW}/file`);
    expect(download.hasAttribute('download')).toBe(true);
    expect(screen.getByRole('button', { name: `Show timeline of ${when}` }).getAttribute('aria-pressed')).toBe('true');

    const timeline = await screen.findByRole('region', { name: `Timeline of ${NEW}` });
    const events = within(timeline).getByRole('list', { name: `Events of ${NEW}` });
    const items = within(events).getAllByTestId('timeline-event');
    expect(items.map((i) => i.getAttribute('data-lane'))).toEqual(['alarms', 'process', 'mode', 'process', 'alarms', 'mode']);
    expect(items[3].textContent).toContain(`${M}3.2 s`);
    expect(items[3].textContent).toContain('error · Move failed');
    expect(within(timeline).getByRole('img').getAttribute('aria-label')).toMatch(/^Alarm at /);
    expect(screen.getByTestId('timeline-marker').textContent).toBe('Alarm');
    expect(screen.getAllByTestId('timeline-tick').map((t) => t.textContent)).toContain('0');
    expect(screen.getAllByTestId('timeline-segment').length).toBe(6);
    expect(screen.getByText('Topics (2)')).toBeTruthy();
  });

  it('"Show timeline" picks another recording; "Delete" asks first and then deletes', async () => {
    render(RecorderPage, { feature, section });
    await screen.findByRole('region', { name: `Timeline of ${NEW}` });
    const oldWhen = formatDate(AT - 86400e3);
    await fireEvent.click(screen.getByRole('button', { name: `Show timeline of ${oldWhen}` }));
    const tl = await screen.findByRole('region', { name: `Timeline of ${OLD}` });
    expect(within(tl).getByTestId('timeline-marker').textContent).toBe('Saved');

    await fireEvent.click(screen.getByRole('button', { name: `Delete recording of ${oldWhen}` }));
    const dialog = screen.getByRole('dialog', { name: `Delete the recording of ${oldWhen}?` });
    await fireEvent.click(within(dialog).getByRole('button', { name: 'Cancel' }));
    expect(calls.some((c) => c.method === 'DELETE')).toBe(false);
    await fireEvent.click(screen.getByRole('button', { name: `Delete recording of ${oldWhen}` }));
    await fireEvent.click(within(screen.getByRole('dialog')).getByRole('button', { name: 'Delete recording' }));
    await vi.waitFor(() => expect(screen.getAllByTestId('recording').length).toBe(1));
    expect(calls.find((c) => c.method === 'DELETE')?.url).toBe(`/api/recorder/recordings/${OLD}`);
    // The deleted one was shown: the newest is shown again.
    expect(await screen.findByRole('region', { name: `Timeline of ${NEW}` })).toBeTruthy();
    expect(screen.getByText(`Deleted the recording of ${oldWhen}.`)).toBeTruthy();
  });

  it('no Delete for a role that may not; the empty list says why there are none', async () => {
    canDelete = false;
    render(RecorderPage, { feature, section });
    await screen.findAllByTestId('recording');
    expect(screen.queryByRole('button', { name: /^Delete recording/ })).toBeNull();
    cleanup();
    list = [];
    render(RecorderPage, { feature, section });
    expect((await screen.findByTestId('recordings-empty')).textContent).toBe('No recordings yet: one is saved around every error alarm.');
    expect(screen.queryByTestId('timeline')).toBeNull();
  });

  it('Save recording calls the service and shows its answer; the state shows pending and errors, a new save reloads', async () => {
    render(RecorderPage, { feature, section });
    await screen.findAllByTestId('recording');
    const saveBtn = screen.getByRole('button', { name: 'Save recording' });
    expect(/** @type {HTMLButtonElement} */ (saveBtn).disabled).toBe(true); // not connected yet
    await connect();
    expect(/** @type {HTMLButtonElement} */ (saveBtn).disabled).toBe(false);
    await fireEvent.click(saveBtn);
    const call = f.calls.find((c) => c.name === '/cell/recorder/save');
    expect(call?.type).toBe('std_srvs/Trigger');
    call?.ok({ success: true, message: 'Saving a recording in 10 s' });
    await vi.waitFor(() => expect(screen.getByTestId('recorder-save-feedback').textContent).toContain('Saving a recording in 10 s'));

    const topic = f.topicsNamed('/cell/recorder/state').find((t) => !t.unsubscribed);
    expect(topic?.type).toBe('cell_msgs/RecorderState');
    const until = (Date.now() + 9500) / 1000;
    topic?.deliver({ pending: 'saved by hand', pending_until: { secs: Math.floor(until), nsecs: Math.round((until % 1) * 1e9) }, last_saved: NEW, error: '', saved_count: 1 });
    flushSync();
    expect(screen.getByTestId('recorder-pending').textContent).toMatch(/^Saving a recording \(saved by hand\) in (9|10) s$/);
    const gets = () => calls.filter((c) => c.url === '/api/recorder/recordings').length;
    const before = gets();
    const NEWER = '20261126T150000.000Z-saved-by-hand.mcap';
    list = [rec(NEWER, AT + 3600e3, { reason: 'saved by hand', alarms: [] }), ...list];
    topic?.deliver({ pending: '', pending_until: { secs: 0, nsecs: 0 }, last_saved: NEWER, error: 'disk full', saved_count: 2 });
    flushSync();
    expect(screen.getByRole('alert').textContent).toBe('The last recording could not be saved: disk full');
    await vi.waitFor(() => expect(gets()).toBe(before + 1));
    await vi.waitFor(() => expect(screen.getAllByTestId('recording').length).toBe(3));
    // Not picked by hand: the newest is shown.
    expect(await screen.findByRole('region', { name: `Timeline of ${NEWER}` })).toBeTruthy();
    expect(screen.getByTestId('recorder-pending').textContent).toBe('');
  });
});
