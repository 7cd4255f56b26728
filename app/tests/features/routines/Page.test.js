// The Routines page against a fake rosbridge (tests/fakeRos.js): a routine records for one motion group, so the
// page shows that group's live pose (its own state topic) and offers that group's tools.
import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, fireEvent, cleanup } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import RoutinesPage from '../../../src/lib/features/routines/Page.svelte';
import { draft } from '../../../src/lib/features/routines/draft.svelte.js';
import { session } from '../../../src/lib/core/session.svelte.js';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { lease } from '../../../src/lib/core/lease.svelte.js';
import { makeFakeFactory, flush } from '../../fakeRos.js';

const feature = { id: 'routines', path: '/routines', title: 'Routines', icon: '', load: async () => ({ default: RoutinesPage }) };
const TWIN = { groups: ['left', 'right'], tools: ['gripper', 'vacuum'], tool_groups: { gripper: 'left', vacuum: 'right' } };
const DRIVER = {
  groups: [{ name: 'left', joints: [], configurations: [] }, { name: 'right', joints: [], configurations: [] }],
  tools: [{ name: 'gripper', actions: ['open', 'close'], group: 'left' }, { name: 'vacuum', actions: ['suction_on', 'suction_off'], group: 'right' }],
};
const STATE = { connected: true, tcp_pose: [0.4, -0.1, 0.3, 0, 3.1416, 0] };

/** @type {ReturnType<typeof makeFakeFactory>} */
let f;

/** @param {any} section @param {string} [username] */
async function open(section, username = 'admin') {
  session.user = { username, role: 'admin' };
  session.config = /** @type {any} */ ({
    cell: { id: 'c', name: 'Twin' }, role: 'admin', pages: [{ id: 'routines', title: 'Routines' }],
    operation_mode: { topic: '/cell/mode', type: 't', modes: [] }, commands: ['routines'], features: { routines: section },
  });
  render(RoutinesPage, { feature });
  ros.start();
  await flush();
  f.rosList.at(-1)?.emit('connection');
  flushSync();
  await vi.waitFor(() => expect(f.calls.some((c) => c.name === '/cell/manual/groups')).toBe(true));
  f.calls.filter((c) => c.name === '/cell/manual/groups').forEach((c) => c.ok(DRIVER));
  f.calls.filter((c) => c.name === '/cell/routines/list').forEach((c) => c.ok({ success: true, routines: [] }));
  await flush();
  flushSync();
}

const live = (/** @type {string} */ name) => f.topicsNamed(name).filter((t) => !t.unsubscribed);
const options = (/** @type {string} */ name) => [.../** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name })).options].map((o) => o.value);

beforeEach(() => {
  ros.stop();
  f = makeFakeFactory();
  ros.factory = f.factory;
  ros.url = () => 'ws://test/ros';
  session.offline = false;
  vi.stubGlobal('fetch', vi.fn(async () => new Response(JSON.stringify({ holder: null, you: false }), { status: 200 })));
  Object.assign(draft, { steps: [], group: '', tool: '', action: '', name: '', owner: '' });
});

afterEach(() => {
  cleanup();
  ros.stop();
  lease.reset();
  vi.unstubAllGlobals();
});

describe('Routines page with two motion groups', () => {
  it('records for the chosen group: its state topic, its tools, the group and tool in the request', async () => {
    await open(TWIN);
    expect(options('Motion group')).toEqual(['left', 'right']);
    expect(live('/cell/manual/left/state').map((t) => t.type)).toEqual(['cell_msgs/RobotState']);
    expect(f.topicsNamed('/cell/manual/state')).toEqual([]);
    expect(options('Tool')).toEqual(['gripper']);
    for (const t of live('/cell/manual/left/state')) t.deliver(STATE);
    flushSync();
    expect(screen.getByTestId('routine-live-pose').textContent).toMatch(/^x 400\.0/);

    await fireEvent.change(screen.getByRole('combobox', { name: 'Motion group' }), { target: { value: 'right' } });
    flushSync();
    expect(f.topicsNamed('/cell/manual/left/state').every((t) => t.unsubscribed)).toBe(true);
    expect(live('/cell/manual/right/state').length).toBe(1);
    expect(screen.getByTestId('routine-live-pose').textContent).toBe('–');
    expect(options('Tool')).toEqual(['vacuum']);
    expect(options('Tool action')).toEqual(['suction_on', 'suction_off']);

    await fireEvent.click(screen.getByRole('button', { name: 'Add pose' }));
    const rec = f.calls.find((c) => c.name === '/cell/routines/record');
    expect(rec?.args).toEqual({ group: 'right', tool: 'vacuum', kind: 'pose', action: '' });
    rec?.ok({ success: true, step: { kind: 'pose', pose: [0.1, 0.2, 0.3, 0, 0, 0], joints: [] } });
    await vi.waitFor(() => expect(screen.getByTestId('routine-draft')).toBeTruthy());
    // A routine is for one group: the group stays while the draft has steps.
    expect(/** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name: 'Motion group' })).disabled).toBe(true);
    expect(screen.getByText(/The recorded steps are for right/)).toBeTruthy();
  });

  it('one group (the demo cell): its state topic and its tools, the group choice as before', async () => {
    await open({ groups: ['arm'], tools: ['gripper'], tool_groups: { gripper: 'arm' } });
    expect(options('Motion group')).toEqual(['arm']);
    expect(live('/cell/manual/arm/state').length).toBe(1);
    expect(options('Tool')).toEqual(['gripper']);
  });
});

describe('recording order', () => {
  it('steps are in the order they were asked for, whichever answer comes first; each as it was when pressed', async () => {
    await open({ groups: ['arm'], tools: ['gripper'], tool_groups: { gripper: 'arm' } });
    const record = () => f.calls.filter((c) => c.name === '/cell/routines/record');
    await fireEvent.click(screen.getByRole('button', { name: 'Add pose' }));
    await fireEvent.change(screen.getByRole('combobox', { name: 'Tool action' }), { target: { value: 'close' } });
    await fireEvent.click(screen.getByRole('button', { name: 'Add action' }));
    await fireEvent.change(screen.getByRole('combobox', { name: 'Tool action' }), { target: { value: 'open' } });
    await flush();
    // The action waits for the pose: asking both at once would let the faster answer go first.
    expect(record().map((c) => c.args.kind)).toEqual(['pose']);
    record()[0].ok({ success: true, step: { kind: 'pose', pose: [0.1, 0.2, 0.3, 0, 0, 0], joints: [] } });
    await vi.waitFor(() => expect(record().length).toBe(2));
    expect(record()[1].args).toEqual({ group: 'arm', tool: 'gripper', kind: 'action', action: 'close' });
    record()[1].ok({ success: true, step: { kind: 'action', tool: 'gripper', action: 'close' } });
    await vi.waitFor(() => expect(screen.getAllByRole('listitem').length).toBe(2));
    expect(screen.getAllByRole('listitem').map((li) => li.textContent?.match(/Pose|Gripper close/)?.[0])).toEqual(['Pose', 'Gripper close']);
    // A refused recording does not hold up the next one.
    await fireEvent.click(screen.getByRole('button', { name: 'Add pose' }));
    await vi.waitFor(() => expect(record().length).toBe(3));
    record()[2].fail('no pose: the driver is not connected');
    await fireEvent.click(screen.getByRole('button', { name: 'Add action' }));
    await vi.waitFor(() => expect(record().length).toBe(4));
  });
});

describe('the draft belongs to the user who recorded it', () => {
  /** Record one pose for `right` and name the draft. */
  async function recordOne() {
    await fireEvent.change(screen.getByRole('combobox', { name: 'Motion group' }), { target: { value: 'right' } });
    flushSync();
    await fireEvent.click(screen.getByRole('button', { name: 'Add pose' }));
    f.calls.find((c) => c.name === '/cell/routines/record')?.ok({ success: true, step: { kind: 'pose', pose: [0.1, 0.2, 0.3, 0, 0, 0], joints: [] } });
    await vi.waitFor(() => expect(screen.getByTestId('routine-draft')).toBeTruthy());
    await fireEvent.input(screen.getByRole('textbox', { name: 'Routine name' }), { target: { value: 'half done' } });
  }

  it('kept for the same user across page changes; empty for the next user who signs in on this phone', async () => {
    await open(TWIN, 'anna');
    await recordOne();
    cleanup();
    ros.stop();

    await open(TWIN, 'anna');
    expect(screen.getAllByRole('listitem').length).toBeGreaterThan(0);
    expect(screen.getByTestId('routine-draft').textContent).toMatch(/Pose/);
    expect(/** @type {HTMLInputElement} */ (screen.getByRole('textbox', { name: 'Routine name' })).value).toBe('half done');
    cleanup();
    ros.stop();

    await open(TWIN, 'ben');
    expect(screen.queryByTestId('routine-draft')).toBeNull();
    expect(/** @type {HTMLInputElement} */ (screen.getByRole('textbox', { name: 'Routine name' })).value).toBe('');
    expect(/** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name: 'Motion group' })).value).toBe('left');
  });
});
