// The Manual motion page against a fake rosbridge (tests/fakeRos.js) on the app's one connection.
import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, fireEvent, within, cleanup } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import ManualPage from '../../../src/lib/features/manual/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { lease } from '../../../src/lib/core/lease.svelte.js';
import { lastKnown } from '../../../src/lib/core/lastKnown.js';
import { makeFakeFactory, flush } from '../../fakeRos.js';

const feature = { id: 'manual', path: '/manual', title: 'Manual motion', icon: '', load: async () => ({ default: ManualPage }) };
const JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint'];
const GROUPS = {
  groups: [
    { name: 'arm', joints: JOINTS, configurations: [{ name: 'home', positions: [0, -1.5708, 1.5708, -1.5708, -1.5708, 0] }, { name: 'pick_approach', positions: [0.4, -1.2, 1.6, -1.97, -1.5708, 0.4] }] },
  ],
  tools: [{ name: 'gripper', actions: ['open', 'close'] }],
  limits: { default_speed: 0.25, default_acceleration: 0.5, max_speed: 1, max_acceleration: 1.5, max_tcp_speed: 0.25, max_tcp_acceleration: 1.2, jog_timeout: 0.2 },
};
/** The cell file's manual section as /api/config gives it (features.manual). */
const SECTION = {
  groups: [{ name: 'arm', joints: JOINTS, configurations: { home: [0, -1.5708, 1.5708, -1.5708, -1.5708, 0], pick_approach: [0.4, -1.2, 1.6, -1.97, -1.5708, 0.4] } }],
  tools: [{ name: 'gripper', actions: [{ name: 'open', steps: [{ digital_out: 0, value: false }] }, { name: 'close', steps: [{ digital_out: 0, value: true }] }] }],
};
const STATE = {
  connected: true, controller: '127.0.0.1', robot_mode: 'RUNNING', safety_mode: 'NORMAL', speed_scaling: 1, program_running: true,
  motion: 'idle', motion_group: '', motion_target: '', progress: 1, message: 'ready',
  joint_positions: [0, -Math.PI / 2, Math.PI / 2, -Math.PI / 2, -Math.PI / 2, 0], tcp_pose: [0.4, -0.1, 0.3, 3.1416, 0, 0], tcp_speed: [0, 0, 0, 0, 0, 0],
};

/** @type {ReturnType<typeof makeFakeFactory>} */
let f;

/** @param {{ you?: boolean, role?: string, commands?: string[], manual?: any }} [o] */
function signIn(o = {}) {
  const role = o.role ?? 'admin';
  session.user = { username: role, role };
  session.config = /** @type {any} */ ({
    cell: { id: 'c', name: 'Demo' }, role, pages: [{ id: 'manual', title: 'Manual motion' }],
    operation_mode: { topic: '/cell/mode', type: 't', modes: [] },
    commands: o.commands ?? (role === 'admin' ? ['manual'] : ['process']),
    features: { manual: o.manual ?? SECTION, video: { streams: [{ name: 'Workbench', topic: '/cell/camera/workbench/image/compressed' }] } },
  });
  const view = o.you ? { holder: { username: role, role }, you: true } : { holder: null, you: false };
  vi.stubGlobal('fetch', vi.fn(async () => new Response(JSON.stringify(view), { status: 200 })));
  lease.you = !!o.you;
  lease.holder = view.holder;
}

async function connect() {
  ros.start();
  await flush();
  f.rosList.at(-1)?.emit('connection');
  flushSync();
}

/** Answer the page's GetMotionGroups call. */
async function answerGroups(resp = GROUPS) {
  await vi.waitFor(() => expect(f.calls.some((c) => c.name === '/cell/manual/groups')).toBe(true));
  f.calls.filter((c) => c.name === '/cell/manual/groups').forEach((c) => c.ok(resp));
  await flush();
  flushSync();
}

/** Deliver a RobotState on a group's state topic (the demo's one group: arm). @param {any} [patch] @param {string} [group] */
function sendState(patch = {}, group = 'arm') {
  for (const t of f.topicsNamed(`/cell/manual/${group}/state`).filter((x) => !x.unsubscribed)) t.deliver({ ...STATE, motion_group: group, ...patch });
  flushSync();
}

const jogTopic = () => f.topicsNamed('/cell/manual/jog').at(-1);
const jogSent = () => /** @type {any[]} */ (jogTopic()?.published ?? []);
/** @param {string} name */
const button = (name) => /** @type {HTMLButtonElement} */ (screen.getByRole('button', { name }));

async function openAsHolder() {
  signIn({ you: true });
  render(ManualPage, { feature });
  await connect();
  await answerGroups();
  sendState();
}

beforeEach(async () => {
  ros.stop();
  f = makeFakeFactory();
  ros.factory = f.factory;
  ros.url = () => 'ws://test/ros';
  session.offline = false;
  sessionStorage.clear();
  await lastKnown.clear();
});

afterEach(() => {
  // Unmount now, and run the page's delayed unadvertise, so no advertisement leaks into the next test.
  vi.useRealTimers();
  vi.useFakeTimers();
  cleanup();
  vi.runOnlyPendingTimers();
  vi.useRealTimers();
  expect(ros.advertisementCount).toBe(0);
  ros.stop();
  lease.reset();
  vi.useRealTimers();
  vi.unstubAllGlobals();
});

describe('Manual motion page', () => {
  it('fills the group, configuration and tool controls from the driver; without control everything that moves is off, with the reason', async () => {
    signIn();
    render(ManualPage, { feature });
    await connect();
    await answerGroups();
    sendState();

    // One motion group: no group choice at all, and the state of that group's topic.
    expect(screen.queryByRole('radiogroup', { name: 'Motion group' })).toBeNull();
    expect(screen.queryByRole('combobox', { name: 'Motion group' })).toBeNull();
    expect(f.topicsNamed('/cell/manual/arm/state').map((t) => t.type)).toEqual(['cell_msgs/RobotState']);
    expect(f.topicsNamed('/cell/manual/state')).toEqual([]);
    const named = /** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name: 'Named configuration' }));
    expect([...named.options].map((o) => o.value)).toEqual(['home', 'pick_approach']);
    for (const n of ['Jog joint 1 +', 'Jog joint 6 -', 'Move to configuration', 'Move relative', 'Move to pose', 'Gripper open', 'Gripper close']) {
      expect(button(n).disabled, n).toBe(true);
    }
    expect(screen.getByTestId('manual-gate').textContent).toMatch(/Take control first/);
    expect(button('Stop move').disabled).toBe(false);
    expect(button('Take control').disabled).toBe(false);
    // The cartesian pad has the X .. RZ buttons.
    await fireEvent.click(screen.getByLabelText('Cartesian jog'));
    for (const n of ['Jog X +', 'Jog X -', 'Jog RZ +', 'Jog RZ -']) expect(button(n)).toBeTruthy();
    expect(screen.queryByRole('button', { name: 'Jog joint 1 +' })).toBeNull();
  });

  it('an operator sees the page read-only, told why; the jog topic is not even advertised; Stop move works', async () => {
    signIn({ role: 'operator' });
    render(ManualPage, { feature });
    await connect();
    await answerGroups();
    sendState();
    for (const n of ['Jog joint 1 +', 'Move to configuration', 'Gripper close']) expect(button(n).disabled).toBe(true);
    expect(screen.getByTestId('manual-gate').textContent).toMatch(/role may not/i);
    expect(f.topicsNamed('/cell/manual/jog')).toEqual([]);
    await fireEvent.click(button('Stop move'));
    const stop = f.calls.find((c) => c.name === '/cell/manual/stop');
    expect(stop?.type).toBe('std_srvs/Trigger');
  });

  it('shows the live pose in mm and rad, the joints in degrees, and the driver status in words', async () => {
    await openAsHolder();
    expect(screen.getByTestId('pose-x').textContent).toBe('400.0');
    expect(screen.getByTestId('pose-y').textContent).toBe('-100.0');
    expect(screen.getByTestId('pose-rx').textContent).toBe('3.1416');
    expect(screen.getByTestId('joint-j2').textContent).toBe('-90.00');
    expect(screen.getByTestId('manual-controller').textContent).toBe('connected to 127.0.0.1');
    expect(screen.getByTestId('manual-robot-mode').textContent).toBe('Running');
    expect(screen.getByTestId('manual-safety-mode').textContent).toBe('Normal');
    expect(screen.getByTestId('manual-pose-freshness').dataset.stale).toBe('false');
    sendState({ motion: 'moving', motion_target: 'home', progress: 0.5, message: 'moving to home' });
    expect(screen.getByTestId('manual-motion').textContent).toBe('moving to home · 50 %');
    expect(/** @type {HTMLProgressElement} */ (screen.getByRole('progressbar', { name: 'Move progress' })).value).toBe(50);
  });

  it('the controller being unreachable closes the controls, with the driver\'s reason', async () => {
    await openAsHolder();
    expect(button('Jog joint 1 +').disabled).toBe(false);
    sendState({ connected: false, message: 'robot controller at 127.0.0.1 is unreachable' });
    expect(button('Jog joint 1 +').disabled).toBe(true);
    expect(button('Move to configuration').disabled).toBe(true);
    expect(screen.getByTestId('manual-gate').textContent).toContain('Robot controller at 127.0.0.1 is unreachable');
  });

  it('hold-to-run: publishes JogCommand at once and every 50 ms while held, one stop on release', async () => {
    await openAsHolder();
    vi.useFakeTimers({ toFake: ['setInterval', 'clearInterval'] });
    const jog = button('Jog joint 1 +');
    expect(jogTopic()?.advertised).toBe(true);
    await fireEvent.pointerDown(jog, { pointerId: 1, button: 0, pointerType: 'touch' });
    expect(jogSent().map(({ press, ...m }) => m)).toEqual([{ group: 'arm', mode: 'joint', axis: 0, direction: 1, speed: 0.25, frame: 'base' }]);
    expect(jog.getAttribute('aria-pressed')).toBe('true');
    vi.advanceTimersByTime(100);
    expect(jogSent().length).toBe(3);
    await fireEvent.pointerUp(jog, { pointerId: 1 });
    await fireEvent(jog, new Event('lostpointercapture'));
    vi.advanceTimersByTime(500);
    expect(jogSent().map((m) => m.direction)).toEqual([1, 1, 1, 0]);
    expect(jog.getAttribute('aria-pressed')).toBe('false');
    expect(screen.queryByTestId('jog-note')).toBeNull(); // the user let go: nothing to explain
  });

  it('a jog the browser ends under a held button (a cancelled touch, the window losing focus) says why; a new press clears it', async () => {
    await openAsHolder();
    const jog = button('Jog joint 2 +');
    await fireEvent.pointerDown(jog, { pointerId: 1, button: 0, pointerType: 'touch' });
    await fireEvent.pointerCancel(jog, { pointerId: 1 });
    expect(jogSent().map((m) => m.direction)).toEqual([1, 0]);
    expect(screen.getByTestId('jog-note').textContent).toBe('Jog stopped: the browser cancelled the touch (a scroll or a system gesture)');
    await fireEvent.pointerDown(jog, { pointerId: 2, button: 0, pointerType: 'touch' });
    expect(screen.queryByTestId('jog-note')).toBeNull();
    await fireEvent.blur(window);
    expect(jogSent().map((m) => m.direction)).toEqual([1, 0, 1, 0]);
    expect(screen.getByTestId('jog-note').textContent).toBe('Jog stopped: the window lost focus');
  });

  it('Cartesian jog in the tool frame, at the chosen jog speed; the pad shows the resulting speeds', async () => {
    await openAsHolder();
    await fireEvent.click(screen.getByLabelText('Cartesian jog'));
    await fireEvent.click(screen.getByLabelText('Tool frame'));
    const slider = screen.getByRole('slider', { name: 'Jog speed' });
    await fireEvent.input(slider, { target: { value: '40' } });
    expect(screen.getByTestId('jog-speed-value').textContent).toContain('100 mm/s · 0.40 rad/s');
    await fireEvent.pointerDown(button('Jog RZ -'), { pointerId: 3, button: 0, pointerType: 'mouse' });
    await fireEvent.pointerUp(button('Jog RZ -'), { pointerId: 3 });
    const press = jogSent()[0].press;
    expect(press).toBeGreaterThan(0);
    expect(jogSent()).toEqual([
      { group: 'arm', mode: 'cartesian', axis: 5, direction: -1, speed: 0.4, frame: 'tool', press },
      { group: 'arm', mode: 'cartesian', axis: 5, direction: 0, speed: 0.4, frame: 'tool', press },
    ]);
  });

  it('Space or Enter held on a jog button jogs too; key up stops', async () => {
    await openAsHolder();
    const jog = button('Jog joint 3 -');
    await fireEvent.keyDown(jog, { key: ' ' });
    await fireEvent.keyDown(jog, { key: ' ', repeat: true });
    expect(jogSent().map((m) => [m.axis, m.direction])).toEqual([[2, -1]]);
    await fireEvent.keyUp(jog, { key: ' ' });
    await fireEvent.keyDown(jog, { key: 'Enter' });
    await fireEvent.keyUp(jog, { key: 'Enter' });
    expect(jogSent().map((m) => m.direction)).toEqual([-1, 0, -1, 0]);
  });

  it('a right click or a press on a closed gate does not jog', async () => {
    signIn();
    render(ManualPage, { feature });
    await connect();
    await answerGroups();
    await fireEvent.pointerDown(button('Jog joint 1 +'), { pointerId: 1, button: 0, pointerType: 'mouse' });
    expect(jogSent()).toEqual([]);
  });

  for (const [what, act] of /** @type {[string, () => void][]} */ ([
    ['control is lost', () => { lease.you = false; }],
    ['the page is hidden', () => {
      Object.defineProperty(document, 'visibilityState', { value: 'hidden', configurable: true });
      document.dispatchEvent(new Event('visibilitychange'));
      // @ts-ignore restore jsdom's own getter
      delete document.visibilityState;
    }],
    ['the window loses focus', () => { window.dispatchEvent(new Event('blur')); }],
    ['the controller becomes unreachable', () => sendState({ connected: false, message: 'robot controller at 127.0.0.1 is unreachable' })],
    ['the app goes offline', () => { session.offline = true; }],
  ])) {
    it(`a held jog stops when ${what}, and nothing is sent after`, async () => {
      await openAsHolder();
      vi.useFakeTimers({ toFake: ['setInterval', 'clearInterval'] });
      await fireEvent.pointerDown(button('Jog joint 2 +'), { pointerId: 1, button: 0, pointerType: 'touch' });
      vi.advanceTimersByTime(50);
      act();
      flushSync();
      vi.advanceTimersByTime(500);
      expect(jogSent().map((m) => m.direction)).toEqual([1, 1, 0]);
    });
  }

  it('a held jog stops when the ROS link drops: no message goes out late on the new socket', async () => {
    await openAsHolder();
    vi.useFakeTimers({ toFake: ['setInterval', 'clearInterval'] });
    await fireEvent.pointerDown(button('Jog joint 1 +'), { pointerId: 1, button: 0, pointerType: 'touch' });
    const first = jogTopic();
    f.rosList.at(-1)?.emit('close');
    flushSync();
    vi.advanceTimersByTime(500);
    expect(/** @type {any[]} */ (first?.published).map((m) => m.direction)).toEqual([1]);
    expect(screen.getByTestId('jog-blocked').textContent).toBe('Not connected to ROS');
  });

  it('leaving the page while holding sends the stop', async () => {
    signIn({ you: true });
    const { unmount } = render(ManualPage, { feature });
    await connect();
    await answerGroups();
    sendState();
    await fireEvent.pointerDown(button('Jog joint 1 +'), { pointerId: 1, button: 0, pointerType: 'touch' });
    vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout'] });
    unmount();
    expect(jogSent().map((m) => m.direction)).toEqual([1, 0]);
    // The topic goes a moment later, so the stop is not cut off by the unadvertise.
    expect(jogTopic()?.unadvertised).toBe(false);
    vi.advanceTimersByTime(1000);
    expect(jogTopic()?.unadvertised).toBe(true);
  });

  it('"Move to configuration" sends group, name and the default speed and acceleration, and shows the driver\'s answer', async () => {
    await openAsHolder();
    await fireEvent.change(screen.getByRole('combobox', { name: 'Named configuration' }), { target: { value: 'pick_approach' } });
    await fireEvent.click(button('Move to configuration'));
    const call = f.calls.find((c) => c.name === '/cell/manual/move_named');
    expect(call?.type).toBe('cell_msgs/MoveNamed');
    expect(call?.args).toEqual({ group: 'arm', name: 'pick_approach', speed: 0.25, acceleration: expect.closeTo(0.5, 6) });
    expect(screen.getByTestId('move-named-feedback').textContent).toContain('Moving…');
    // While it runs, the jog pad says why it is off.
    expect(button('Jog joint 1 +').disabled).toBe(true);
    expect(screen.getByTestId('jog-blocked').textContent).toMatch(/move is running/);
    call?.ok({ success: true, message: 'arrived at pick_approach' });
    await vi.waitFor(() => expect(screen.getByTestId('move-named-feedback').textContent).toContain('arrived at pick_approach'));
    expect(button('Jog joint 1 +').disabled).toBe(false);
  });

  it('a refused move shows the driver\'s message', async () => {
    await openAsHolder();
    await fireEvent.click(button('Move to configuration'));
    f.calls.find((c) => c.name === '/cell/manual/move_named')?.ok({ success: false, message: 'protective stop is active: clear it first' });
    await vi.waitFor(() => expect(screen.getByTestId('move-named-feedback').textContent).toContain('Failed: protective stop is active: clear it first'));
  });

  it('"Move relative" converts mm and degrees; "Move to pose" takes the current pose', async () => {
    await openAsHolder();
    await fireEvent.input(screen.getByLabelText('dZ (mm)'), { target: { value: '-20' } });
    await fireEvent.input(screen.getByLabelText('dRZ (deg)'), { target: { value: '90' } });
    await fireEvent.change(screen.getByRole('combobox', { name: 'Relative move frame' }), { target: { value: 'tool' } });
    await fireEvent.click(button('Move relative'));
    const rel = f.calls.find((c) => c.name === '/cell/manual/move_relative');
    expect(rel?.args.frame).toBe('tool');
    expect(rel?.args.offset.map((/** @type {number} */ v) => Math.round(v * 1e6) / 1e6)).toEqual([0, 0, -0.02, 0, 0, 1.570796]);
    expect(rel?.args.speed).toBeCloseTo(0.0625, 6); // 25 % of 250 mm/s
    rel?.ok({ success: true, message: 'arrived (relative)' });

    await fireEvent.click(button('Use current pose'));
    await vi.waitFor(() => expect(/** @type {HTMLInputElement} */ (screen.getByLabelText('X (mm)')).value).toBe('400.00'));
    await fireEvent.input(screen.getByLabelText('Z (mm)'), { target: { value: '250' } });
    await fireEvent.click(button('Move to pose'));
    const pose = f.calls.find((c) => c.name === '/cell/manual/move_pose');
    expect(pose?.type).toBe('cell_msgs/MovePose');
    expect(pose?.args.group).toBe('arm');
    expect(pose?.args.pose).toEqual([0.4, -0.1, 0.25, 3.1416, 0, 0]);
  });

  it('a relative move with nothing entered is not sent, and says why', async () => {
    await openAsHolder();
    await fireEvent.click(button('Move relative'));
    await vi.waitFor(() => expect(screen.getByTestId('move-relative-feedback').textContent).toMatch(/Enter an offset/));
    expect(f.calls.some((c) => c.name === '/cell/manual/move_relative')).toBe(false);
  });

  it('tool buttons call the tool action', async () => {
    await openAsHolder();
    await fireEvent.click(button('Gripper close'));
    const call = f.calls.find((c) => c.name === '/cell/manual/tool');
    expect(call?.args).toEqual({ tool: 'gripper', action: 'close' });
    call?.ok({ success: true, message: 'gripper close done' });
    await vi.waitFor(() => expect(screen.getByTestId('tool-gripper-close-feedback').textContent).toContain('gripper close done'));
  });

  it('asks the driver for its groups again after a reconnect', async () => {
    await openAsHolder();
    const n = f.calls.filter((c) => c.name === '/cell/manual/groups').length;
    f.rosList.at(-1)?.emit('close');
    flushSync();
    expect(screen.getByTestId('last-known').textContent).toContain('ROS disconnected');
    expect(screen.getByTestId('manual-pose-freshness').dataset.stale).toBe('true');
    await new Promise((r) => setTimeout(r, 600)); // the connection's first backoff
    f.rosList.at(-1)?.emit('connection');
    flushSync();
    await vi.waitFor(() => expect(f.calls.filter((c) => c.name === '/cell/manual/groups').length).toBe(n + 1));
  });

  it('asks the driver for its groups again when its controller link comes back', async () => {
    await openAsHolder();
    const groupCalls = () => f.calls.filter((c) => c.name === '/cell/manual/groups').length;
    const n = groupCalls();
    sendState({ connected: true });
    expect(groupCalls()).toBe(n);
    sendState({ connected: false, message: 'robot controller at 127.0.0.1 is unreachable' });
    sendState({ connected: true });
    await vi.waitFor(() => expect(groupCalls()).toBe(n + 1));
  });

  it('keeps the last state in IndexedDB and shows it, stale, on a later visit without ROS', async () => {
    await openAsHolder();
    await vi.waitFor(async () => expect((await lastKnown.load('manual/arm', { user: 'admin' }))?.data.state.tcp_pose[0]).toBe(0.4));
    screen.getByTestId('manual-status'); // rendered
    ros.stop();
    document.body.innerHTML = '';
    render(ManualPage, { feature });
    await vi.waitFor(() => expect(screen.getByTestId('pose-x').textContent).toBe('400.0'));
    expect(screen.getByTestId('manual-pose-freshness').dataset.stale).toBe('true');
    expect(within(screen.getByTestId('manual-status')).getByTestId('manual-robot-mode').textContent).toBe('Running');
  });

  it('has no camera on a phone (no wide media match)', async () => {
    await openAsHolder();
    expect(screen.queryByTestId('manual-camera')).toBeNull();
    expect(f.topicsNamed('/cell/camera/workbench/image/compressed')).toEqual([]);
  });

  it('on a tablet or PC: a camera beside the controls, subscribed only while shown', async () => {
    vi.stubGlobal('matchMedia', (/** @type {string} */ q) => ({ matches: q.includes('768px'), addEventListener: () => {}, removeEventListener: () => {} }));
    await openAsHolder();
    expect(screen.getByTestId('manual-camera')).toBeTruthy();
    expect(screen.getByRole('combobox', { name: 'Camera' })).toBeTruthy();
    const cam = f.topicsNamed('/cell/camera/workbench/image/compressed');
    expect(cam.length).toBe(1);
    expect(cam[0].type).toBe('sensor_msgs/CompressedImage');
    vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout'] });
    cleanup();
    vi.runOnlyPendingTimers();
    expect(cam[0].unsubscribed).toBe(true);
  });
});

// ---- a cell with two motion groups (as config/twin-arm-cell.yaml): one UR arm each, a tool on each ----
const prefixed = (/** @type {string} */ p) => JOINTS.map((j) => `${p}_${j}`);
const TWIN_GROUPS = {
  groups: [
    { name: 'left', joints: prefixed('left'), configurations: [{ name: 'home', positions: [0, -1.5708, 1.5708, -1.5708, -1.5708, 0] }, { name: 'handover', positions: [0.8, -1.2, 1.6, -1.97, -1.5708, 0] }] },
    { name: 'right', joints: prefixed('right'), configurations: [{ name: 'home', positions: [0, -1.5708, 1.5708, -1.5708, -1.5708, 0] }, { name: 'place', positions: [-0.6, -1.2, 1.6, -1.97, -1.5708, 0] }] },
  ],
  // The lamp has no group in the answer (an older driver): it belongs to the first group.
  tools: [{ name: 'gripper', actions: ['open', 'close'], group: 'left' }, { name: 'vacuum', actions: ['suction_on', 'suction_off'], group: 'right' }, { name: 'lamp', actions: ['on'] }],
  limits: GROUPS.limits,
};
const TWIN_SECTION = {
  groups: TWIN_GROUPS.groups.map((g) => ({ name: g.name, joints: g.joints, configurations: Object.fromEntries(g.configurations.map((c) => [c.name, c.positions])) })),
  tools: [{ name: 'gripper', actions: [] }, { name: 'vacuum', group: 'right', actions: [] }, { name: 'lamp', actions: [] }],
};

/** @param {{ you?: boolean, role?: string }} [o] */
async function openTwin(o = {}) {
  signIn({ ...o, manual: TWIN_SECTION });
  const r = render(ManualPage, { feature });
  await connect();
  await answerGroups(TWIN_GROUPS);
  sendState({}, 'left');
  return r;
}

const groupRadio = (/** @type {string} */ name) => /** @type {HTMLInputElement} */ (screen.getByRole('radio', { name }));
const liveTopics = (/** @type {string} */ name) => f.topicsNamed(name).filter((t) => !t.unsubscribed);
/** Unmount (or clean up) now and run the page's delayed unadvertise, as a page change would. @param {() => void} fn */
function leave(fn) {
  vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout'] });
  fn();
  vi.runOnlyPendingTimers();
  vi.useRealTimers();
}
const configOptions = () => [.../** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name: 'Named configuration' })).options].map((o) => o.value);

describe('Manual motion page with two motion groups', () => {
  it('the group comes first: a "Motion group" radio group, one option per group, the first chosen; the page is for it', async () => {
    await openTwin();
    const chooser = screen.getByRole('radiogroup', { name: 'Motion group' });
    expect(within(chooser).getAllByRole('radio').map((r) => r.getAttribute('value'))).toEqual(['left', 'right']);
    expect(groupRadio('left').checked).toBe(true);
    expect(groupRadio('right').checked).toBe(false);
    // Its state only, its configurations, its tools (the lamp has no group: the first group's).
    expect(liveTopics('/cell/manual/left/state').length).toBe(1);
    expect(f.topicsNamed('/cell/manual/right/state')).toEqual([]);
    expect(configOptions()).toEqual(['home', 'handover']);
    for (const n of ['Gripper open', 'Gripper close', 'Lamp on']) expect(button(n)).toBeTruthy();
    expect(screen.queryByRole('button', { name: 'Vacuum suction on' })).toBeNull();
    expect(screen.getByTestId('manual-status-group').textContent).toBe('left');
    // Joint names carry the group prefix; the page shows the UR joint.
    expect(screen.getByTestId('manual-pose').querySelector('[title="shoulder pan"]')).toBeTruthy();
    // The chooser sits before the status strip (chosen first, then everything for it).
    expect(chooser.compareDocumentPosition(screen.getByTestId('manual-status')) & Node.DOCUMENT_POSITION_FOLLOWING).toBeTruthy();
  });

  it('choosing another group re-subscribes to its state and shows its pose, configurations and tools', async () => {
    await openTwin();
    expect(screen.getByTestId('pose-x').textContent).toBe('400.0');
    await fireEvent.click(groupRadio('right'));
    flushSync();
    expect(groupRadio('right').checked).toBe(true);
    expect(f.topicsNamed('/cell/manual/left/state').every((t) => t.unsubscribed)).toBe(true);
    expect(liveTopics('/cell/manual/right/state').map((t) => t.type)).toEqual(['cell_msgs/RobotState']);
    // Nothing of the left arm is shown as the right one's.
    expect(screen.getByTestId('pose-x').textContent).toBe('—');
    sendState({ tcp_pose: [-0.3, 0.2, 0.25, 0, 3.1416, 0], controller: '127.0.2.2' }, 'right');
    expect(screen.getByTestId('pose-x').textContent).toBe('-300.0');
    expect(screen.getByTestId('manual-controller').textContent).toBe('connected to 127.0.2.2');
    expect(screen.getByTestId('manual-status-group').textContent).toBe('right');
    expect(configOptions()).toEqual(['home', 'place']);
    for (const n of ['Vacuum suction on', 'Vacuum suction off']) expect(button(n)).toBeTruthy();
    for (const n of ['Gripper open', 'Lamp on']) expect(screen.queryByRole('button', { name: n })).toBeNull();
    // Back to left: its subscription again.
    await fireEvent.click(groupRadio('left'));
    flushSync();
    expect(liveTopics('/cell/manual/left/state').length).toBe(1);
    expect(f.topicsNamed('/cell/manual/right/state').every((t) => t.unsubscribed)).toBe(true);
  });

  it('jog, moves and tool actions go with the chosen group', async () => {
    await openTwin({ you: true });
    await fireEvent.click(groupRadio('right'));
    sendState({}, 'right');
    await fireEvent.pointerDown(button('Jog joint 2 +'), { pointerId: 1, button: 0, pointerType: 'touch' });
    await fireEvent.pointerUp(button('Jog joint 2 +'), { pointerId: 1 });
    expect(jogSent().map((m) => [m.group, m.axis, m.direction])).toEqual([['right', 1, 1], ['right', 1, 0]]);
    await fireEvent.change(screen.getByRole('combobox', { name: 'Named configuration' }), { target: { value: 'place' } });
    await fireEvent.click(button('Move to configuration'));
    expect(f.calls.find((c) => c.name === '/cell/manual/move_named')?.args).toMatchObject({ group: 'right', name: 'place' });
    f.calls.find((c) => c.name === '/cell/manual/move_named')?.ok({ success: true, message: 'arrived at place' });
    await vi.waitFor(() => expect(button('Move to configuration').disabled).toBe(false));
    await fireEvent.click(button('Vacuum suction on'));
    expect(f.calls.find((c) => c.name === '/cell/manual/tool')?.args).toEqual({ tool: 'vacuum', action: 'suction_on' });
  });

  it('switching the group while jogging stops the jog first (the stop goes to the jogging arm), and nothing follows', async () => {
    await openTwin({ you: true });
    vi.useFakeTimers({ toFake: ['setInterval', 'clearInterval'] });
    await fireEvent.pointerDown(button('Jog joint 1 +'), { pointerId: 1, button: 0, pointerType: 'touch' });
    vi.advanceTimersByTime(50);
    await fireEvent.click(groupRadio('right'));
    flushSync();
    vi.advanceTimersByTime(500);
    expect(jogSent().map((m) => [m.group, m.direction])).toEqual([['left', 1], ['left', 1], ['left', 0]]);
    expect(button('Jog joint 1 +').getAttribute('aria-pressed')).toBe('false');
  });

  it('"Stop move" is one call that stops every arm, whichever group is shown', async () => {
    await openTwin();
    await fireEvent.click(groupRadio('right'));
    await fireEvent.click(button('Stop move'));
    const stops = f.calls.filter((c) => c.name === '/cell/manual/stop');
    expect(stops.map((c) => [c.type, c.args])).toEqual([['std_srvs/Trigger', {}]]);
  });

  it('the choice is remembered for the session (another visit, a reload); an unknown one falls back to the first group', async () => {
    const { unmount } = await openTwin();
    await fireEvent.click(groupRadio('right'));
    expect(sessionStorage.getItem('cell-ui.manual.group')).toBe('right');
    leave(unmount);
    render(ManualPage, { feature });
    await answerGroups(TWIN_GROUPS);
    expect(groupRadio('right').checked).toBe(true);
    expect(liveTopics('/cell/manual/right/state').length).toBe(1);
    expect(liveTopics('/cell/manual/left/state')).toEqual([]);
    leave(cleanup);
    sessionStorage.setItem('cell-ui.manual.group', 'middle');
    render(ManualPage, { feature });
    expect(groupRadio('left').checked).toBe(true);
  });

  it('before the driver answers, the groups come from the cell file: the choice and the state are there at once', async () => {
    signIn({ manual: TWIN_SECTION });
    render(ManualPage, { feature });
    await connect();
    expect(within(screen.getByRole('radiogroup', { name: 'Motion group' })).getAllByRole('radio').length).toBe(2);
    expect(liveTopics('/cell/manual/left/state').length).toBe(1);
    sendState({}, 'left');
    expect(screen.getByTestId('pose-x').textContent).toBe('400.0');
    expect(screen.getByTestId('manual-setup').textContent).toMatch(/Asking the robot driver/);
  });

  it('each group keeps its own last known state', async () => {
    await openTwin();
    await vi.waitFor(async () => expect((await lastKnown.load('manual/left', { user: 'admin' }))?.data.state.tcp_pose[0]).toBe(0.4));
    await fireEvent.click(groupRadio('right'));
    sendState({ tcp_pose: [-0.3, 0.2, 0.25, 0, 3.1416, 0] }, 'right');
    f.rosList.at(-1)?.emit('close');
    flushSync();
    await vi.waitFor(async () => expect((await lastKnown.load('manual/right', { user: 'admin' }))?.data.state.tcp_pose[0]).toBe(-0.3));
    expect((await lastKnown.load('manual/left', { user: 'admin' }))?.data.state.tcp_pose[0]).toBe(0.4);
    // Offline, the other group shows its own last state, stale.
    await fireEvent.click(groupRadio('left'));
    await vi.waitFor(() => expect(screen.getByTestId('pose-x').textContent).toBe('400.0'));
    expect(screen.getByTestId('manual-pose-freshness').dataset.stale).toBe('true');
  });
});
