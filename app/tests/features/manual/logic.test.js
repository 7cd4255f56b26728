// @vitest-environment node
import { describe, it, expect, vi, afterEach } from 'vitest';
import {
  mmToM, mToMm, degToRad, radToDeg, parseNumber, fixed, normalizeLimits, normalizeSetup, humanize, toolLabel, jogLabel,
  jogRows, jointShortName, defaultFraction, jogRates, moveRates, jogCommand, namedRequest, relativeRequest, poseRequest,
  poseToForm, poseRows, jointRows, modeText, robotModeTone, safetyTone, pickState, statusView, manualGate, notLiveBecause,
  JogHold, JOG_PERIOD_MS, MAX_MANUAL_TCP_SPEED, VIEW_ONLY_REASON, stateTopic, STATE_TYPE, sectionGroups, groupChoices,
  chosenGroup, toolsOfGroup, jogStopNote,
} from '../../../src/lib/features/manual/logic.js';

const LIMITS = normalizeLimits({
  default_speed: 0.25, default_acceleration: 0.5, max_speed: 1.0, max_acceleration: 1.5,
  max_tcp_speed: 0.2, max_tcp_acceleration: 1.2, jog_timeout: 0.2,
});

describe('units and numbers', () => {
  it('converts mm/m and deg/rad both ways', () => {
    expect(mmToM(250)).toBe(0.25);
    expect(mToMm(0.0125)).toBeCloseTo(12.5, 12);
    expect(degToRad(180)).toBeCloseTo(Math.PI, 12);
    expect(radToDeg(Math.PI / 2)).toBeCloseTo(90, 12);
    expect(radToDeg(degToRad(-37.5))).toBeCloseTo(-37.5, 12);
  });

  it('parses what a shop-floor keyboard types, and nothing else', () => {
    expect(parseNumber('12.5')).toBe(12.5);
    expect(parseNumber(' -3 ')).toBe(-3);
    expect(parseNumber('1,5')).toBe(1.5);
    expect(parseNumber('+.5')).toBe(0.5);
    expect(parseNumber('1e-3')).toBe(0.001);
    expect(parseNumber(7)).toBe(7);
    for (const bad of ['', '  ', 'abc', '1.2.3', '12mm', NaN, Infinity, null, undefined, '0x10']) expect(parseNumber(bad)).toBeNull();
  });

  it('formats fixed digits, a dash for no number, and never "-0.0"', () => {
    expect(fixed(1.23456, 2)).toBe('1.23');
    expect(fixed(-0.00001, 3)).toBe('0.000');
    expect(fixed(-0.4, 0)).toBe('0');
    expect(fixed(-1.5, 1)).toBe('-1.5');
    expect(fixed(undefined, 2)).toBe('—');
    expect(fixed(NaN, 2)).toBe('—');
  });
});

describe("the driver's groups, tools and limits", () => {
  it('keeps the TCP speed limit at 250 mm/s whatever the driver says', () => {
    expect(normalizeLimits({ max_tcp_speed: 1.5 }).maxTcpSpeed).toBe(MAX_MANUAL_TCP_SPEED);
    expect(normalizeLimits({ max_tcp_speed: 0.1 }).maxTcpSpeed).toBe(0.1);
    expect(normalizeLimits({}).maxTcpSpeed).toBe(MAX_MANUAL_TCP_SPEED);
    expect(normalizeLimits(null).maxSpeed).toBe(0);
    expect(normalizeLimits({ max_speed: -1, default_speed: 'x' })).toMatchObject({ maxSpeed: 0, defaultSpeed: 0 });
  });

  it('normalises the GetMotionGroups answer, dropping unnamed entries', () => {
    const s = normalizeSetup({
      groups: [
        { name: 'arm', joints: ['shoulder_pan_joint', 7], configurations: [{ name: 'home', positions: [0, -1.57] }, { positions: [1] }] },
        { joints: ['x'] },
      ],
      tools: [{ name: 'gripper', actions: ['open', 'close'] }, { name: '' }, { name: 'vacuum', actions: ['on'], group: 'right' }],
      limits: { max_speed: 1 },
    });
    expect(s.groups).toEqual([{ name: 'arm', joints: ['shoulder_pan_joint'], configurations: [{ name: 'home', positions: [0, -1.57] }] }]);
    // ToolInfo.group: '' when the driver does not say (the first group's).
    expect(s.tools).toEqual([{ name: 'gripper', actions: ['open', 'close'], group: '' }, { name: 'vacuum', actions: ['on'], group: 'right' }]);
    expect(s.limits.maxSpeed).toBe(1);
    expect(normalizeSetup(undefined)).toMatchObject({ groups: [], tools: [] });
  });
});

describe('names', () => {
  it('names tool buttons "Gripper open" and jog buttons as the e2e tests expect', () => {
    expect(humanize('tool_changer')).toBe('Tool changer');
    expect(toolLabel('gripper', 'open')).toBe('Gripper open');
    expect(toolLabel('gripper', 'close')).toBe('Gripper close');
    expect(toolLabel('tool_changer', 'release_tool')).toBe('Tool changer release tool');
    // The cell file's title of the action, in the user's language (manual.tools[].actions[].title).
    const section = { tools: [{ name: 'gripper', actions: [{ name: 'close', title: { en: 'Close the gripper', de: 'Greifer schließen' } }, { name: 'open' }] }] };
    expect(toolLabel('gripper', 'close', section)).toBe('Close the gripper');
    expect(toolLabel('gripper', 'open', section)).toBe('Gripper open');
    // (in German: said.test.js, which has a locale)
    expect(jogLabel('joint', 0, 1)).toBe('Jog joint 1 +');
    expect(jogLabel('joint', 5, -1)).toBe('Jog joint 6 -');
    expect(jogLabel('cartesian', 0, 1)).toBe('Jog X +');
    expect(jogLabel('cartesian', 5, -1)).toBe('Jog RZ -');
  });

  it('has one jog row per joint of the group, or per Cartesian axis', () => {
    const joints = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint'];
    expect(jogRows('joint', joints).map((r) => [r.axis, r.name, r.detail])).toEqual([
      [0, 'J1', 'shoulder pan'], [1, 'J2', 'shoulder lift'], [2, 'J3', 'elbow'],
    ]);
    expect(jogRows('cartesian', joints).map((r) => r.name)).toEqual(['X', 'Y', 'Z', 'RX', 'RY', 'RZ']);
    expect(jointShortName('wrist_1_joint')).toBe('wrist 1');
    // A cell with several arms prefixes its joint names: the pad shows the UR joint the name ends with.
    expect(jointShortName('left_shoulder_pan_joint')).toBe('shoulder pan');
    expect(jointShortName('right_wrist_3_joint')).toBe('wrist 3');
    expect(jointShortName('gantry_x_joint')).toBe('gantry x');
  });
});

describe('motion groups', () => {
  const twin = {
    groups: [
      { name: 'left', joints: ['left_shoulder_pan_joint'], configurations: { home: [0, 1], handover: [2, 3] }, host: '127.0.2.1' },
      { name: 'right', joints: ['right_shoulder_pan_joint'] },
    ],
    tools: [{ name: 'gripper', actions: [] }, { name: 'vacuum', group: 'right', actions: [] }],
  };

  it('each group has its own state topic', () => {
    expect(stateTopic('arm')).toBe('/cell/manual/arm/state');
    expect(stateTopic('left')).toBe('/cell/manual/left/state');
    expect(STATE_TYPE).toBe('cell_msgs/RobotState');
  });

  it('reads the groups of the cell file\'s section as the driver describes them', () => {
    expect(sectionGroups(twin)).toEqual([
      { name: 'left', joints: ['left_shoulder_pan_joint'], configurations: [{ name: 'home', positions: [0, 1] }, { name: 'handover', positions: [2, 3] }] },
      { name: 'right', joints: ['right_shoulder_pan_joint'], configurations: [] },
    ]);
    expect(sectionGroups(null)).toEqual([]);
    expect(sectionGroups({ groups: [{ joints: [] }] })).toEqual([]);
  });

  it('offers the driver\'s groups once it answered, the cell file\'s before; the remembered one while it exists', () => {
    const fromCell = sectionGroups(twin);
    expect(groupChoices(null, fromCell)).toEqual(['left', 'right']);
    const setup = normalizeSetup({ groups: [{ name: 'arm', joints: ['a'] }] });
    expect(groupChoices(setup, fromCell)).toEqual(['arm']);
    expect(groupChoices(normalizeSetup({}), fromCell)).toEqual(['left', 'right']);
    expect(chosenGroup(['left', 'right'], 'right')).toBe('right');
    expect(chosenGroup(['left', 'right'], 'middle')).toBe('left');
    expect(chosenGroup(['left', 'right'], '')).toBe('left');
    expect(chosenGroup([], 'right')).toBe('');
  });

  it('a tool belongs to the group the driver says, else the cell file says, else the first group', () => {
    const tools = [
      { name: 'gripper', actions: ['open'], group: 'left' },
      { name: 'vacuum', actions: ['on'], group: '' },
      { name: 'lamp', actions: ['on'], group: '' },
    ];
    expect(toolsOfGroup(tools, 'left', 'left', twin).map((t) => t.name)).toEqual(['gripper', 'lamp']);
    expect(toolsOfGroup(tools, 'right', 'left', twin).map((t) => t.name)).toEqual(['vacuum']);
    expect(toolsOfGroup(tools, 'right', 'left').map((t) => t.name)).toEqual([]);
    expect(toolsOfGroup([{ name: 'gripper', actions: [], group: '' }], 'arm', 'arm').map((t) => t.name)).toEqual(['gripper']);
  });
});

describe('speeds', () => {
  it('starts the sliders at the default over the maximum, within (0, 1]', () => {
    expect(defaultFraction(0.25, 1)).toBe(0.25);
    expect(defaultFraction(5, 1)).toBe(1);
    expect(defaultFraction(0, 1)).toBe(0.25);
    expect(defaultFraction(0.5, 0, 0.3)).toBe(0.3);
    expect(defaultFraction(0.0001, 1)).toBe(0.01);
  });

  it('jog rates: mm/s from the TCP limit (<= 250 mm/s), rad/s from the joint limit', () => {
    expect(jogRates(0.5, LIMITS)).toEqual({ mmPerS: 100, radPerS: 0.5 });
    expect(jogRates(1, normalizeLimits({ max_speed: 2, max_tcp_speed: 3 }))).toEqual({ mmPerS: 250, radPerS: 2 });
    expect(jogRates(7, LIMITS).radPerS).toBe(1);
  });

  it('move rates: joint moves in rad/s, Cartesian moves in m/s, both within the limits', () => {
    const r = moveRates(0.5, 0.2, LIMITS);
    expect(r.joint.speed).toBeCloseTo(0.5);
    expect(r.joint.acceleration).toBeCloseTo(0.3);
    expect(r.tcp.speed).toBeCloseTo(0.1);
    expect(r.tcp.acceleration).toBeCloseTo(0.24);
    const top = moveRates(3, 3, LIMITS);
    expect(top.tcp.speed).toBeLessThanOrEqual(MAX_MANUAL_TCP_SPEED);
    expect(top.joint.speed).toBe(1);
    expect(moveRates(0, 0, LIMITS).joint.speed).toBeGreaterThan(0); // 0 would mean "the driver's default"
  });
});

describe('messages and service requests', () => {
  it('builds a JogCommand with a clamped speed fraction and a +1/-1/0 direction', () => {
    expect(jogCommand({ group: 'arm', mode: 'joint', axis: 2, direction: 5, fraction: 1.7, frame: 'tool' })).toEqual({
      group: 'arm', mode: 'joint', axis: 2, direction: 1, speed: 1, frame: 'tool',
    });
    expect(jogCommand({ group: 'arm', mode: 'cartesian', axis: 0, direction: -1, fraction: 0, frame: /** @type {any} */ ('x') })).toMatchObject({
      direction: -1, speed: 0.01, frame: 'base',
    });
  });

  it('MoveNamed: group, name, rad/s, rad/s^2', () => {
    expect(namedRequest('arm', 'home', { speed: 0.25, acceleration: 0.5 })).toEqual({ ok: true, request: { group: 'arm', name: 'home', speed: 0.25, acceleration: 0.5 } });
    expect(namedRequest('arm', '', { speed: 0.25, acceleration: 0.5 })).toMatchObject({ ok: false });
    expect(namedRequest('', 'home', { speed: 0.25, acceleration: 0.5 })).toMatchObject({ ok: false });
  });

  it('MoveRelative: mm become m, degrees become rad (a rotation vector), empty fields are 0', () => {
    const b = relativeRequest('arm', { dx: '10', dy: '-2,5', dz: '', drx: '90', dry: '', drz: '-180' }, 'tool', { speed: 0.1, acceleration: 0.5 });
    expect(b.ok).toBe(true);
    if (!b.ok) return;
    expect(b.request.group).toBe('arm');
    expect(b.request.frame).toBe('tool');
    expect(b.request.speed).toBe(0.1);
    const expected = [0.01, -0.0025, 0, Math.PI / 2, 0, -Math.PI];
    b.request.offset.forEach((/** @type {number} */ v, /** @type {number} */ i) => expect(v).toBeCloseTo(expected[i], 12));
  });

  it('MoveRelative refuses an all-zero offset and a field that is not a number', () => {
    const r = { speed: 0.1, acceleration: 0.5 };
    expect(relativeRequest('arm', { dx: '', dy: '0', dz: '', drx: '', dry: '', drz: '' }, 'base', r)).toMatchObject({ ok: false, error: expect.stringMatching(/offset/) });
    expect(relativeRequest('arm', { dx: '1x', dy: '', dz: '', drx: '', dry: '', drz: '' }, 'base', r)).toMatchObject({ ok: false, error: expect.stringMatching(/dx/) });
  });

  it('MovePose: mm become m, rotations stay rad; every field is needed', () => {
    const b = poseRequest('arm', { x: '400', y: '-100.5', z: '300', rx: '3.1416', ry: '0', rz: '-0.5' }, { speed: 0.05, acceleration: 0.3 });
    expect(b).toMatchObject({ ok: true });
    if (b.ok) {
      expect(b.request.pose[0]).toBeCloseTo(0.4, 12);
      expect(b.request.pose[1]).toBeCloseTo(-0.1005, 12);
      expect(b.request.pose.slice(3)).toEqual([3.1416, 0, -0.5]);
      expect(b.request).toMatchObject({ group: 'arm', speed: 0.05, acceleration: 0.3 });
    }
    expect(poseRequest('arm', { x: '400', y: '', z: '300', rx: '0', ry: '0', rz: '0' }, { speed: 0.05, acceleration: 0.3 })).toMatchObject({ ok: false });
  });

  it('"Use current pose" fills the pose form in mm and rad, and round-trips', () => {
    const tcp = [0.4123456, -0.1, 0.3, 3.14159265, 0.001, -0.5];
    const f = poseToForm(tcp);
    expect(f).toEqual({ x: '412.35', y: '-100.00', z: '300.00', rx: '3.1416', ry: '0.0010', rz: '-0.5000' });
    const back = poseRequest('arm', /** @type {any} */ (f), { speed: 0.1, acceleration: 0.1 });
    if (back.ok) back.request.pose.forEach((/** @type {number} */ v, /** @type {number} */ i) => expect(Math.abs(v - tcp[i])).toBeLessThan(1e-4));
    expect(poseToForm([1, 2])).toBeNull();
    expect(poseToForm(null)).toBeNull();
  });
});

describe('what the page shows', () => {
  it('shows the TCP as X, Y, Z in mm and RX, RY, RZ in rad (no quaternion)', () => {
    expect(poseRows([0.1234, -0.5, 0, 3.14159, 0, -1.2])).toEqual([
      { label: 'X', value: '123.4', unit: 'mm' }, { label: 'Y', value: '-500.0', unit: 'mm' }, { label: 'Z', value: '0.0', unit: 'mm' },
      { label: 'RX', value: '3.1416', unit: 'rad' }, { label: 'RY', value: '0.0000', unit: 'rad' }, { label: 'RZ', value: '-1.2000', unit: 'rad' },
    ]);
    expect(poseRows(undefined).every((r) => r.value === '—')).toBe(true);
  });

  it('shows joints in degrees with the group joint names', () => {
    expect(jointRows([0, -Math.PI / 2], ['shoulder_pan_joint', 'shoulder_lift_joint'])).toEqual([
      { label: 'J1', name: 'shoulder pan', value: '0.00' }, { label: 'J2', name: 'shoulder lift', value: '-90.00' },
    ]);
    expect(jointRows(undefined, ['a_joint'])).toEqual([{ label: 'J1', name: 'a', value: '—' }]);
  });

  it('says robot and safety modes in words, with a tone', () => {
    expect(modeText('POWER_OFF')).toBe('Power off');
    expect(modeText('PROTECTIVE_STOP')).toBe('Protective stop');
    expect(robotModeTone('RUNNING')).toBe('ok');
    expect(robotModeTone('POWER_OFF')).toBe('warn');
    expect(robotModeTone('NO_CONTROLLER')).toBe('danger');
    expect(safetyTone('NORMAL')).toBe('ok');
    expect(safetyTone('REDUCED')).toBe('warn');
    expect(safetyTone('PROTECTIVE_STOP')).toBe('danger');
  });

  it('builds the status strip from RobotState', () => {
    const s = pickState({
      connected: true, controller: '10.0.0.2', robot_mode: 'RUNNING', safety_mode: 'NORMAL', motion: 'moving',
      motion_group: 'arm', motion_target: 'home', progress: 0.42, message: 'moving to home', joint_positions: [0, 1], tcp_pose: [1, 2, 3, 0, 0, 0],
    });
    const v = statusView(s);
    expect(v.driver).toEqual({ text: 'connected to 10.0.0.2', tone: 'ok' });
    expect(v.robot.text).toBe('Running');
    expect(v.safety.text).toBe('Normal');
    expect(v.motion).toEqual({ text: 'moving to home', moving: true, progress: 0.42 });
    const down = statusView(pickState({ connected: false, controller: '10.0.0.2', message: 'robot controller at 10.0.0.2 is unreachable' }));
    expect(down.driver).toEqual({ text: 'unreachable (10.0.0.2)', tone: 'danger' });
    expect(down.motion.moving).toBe(false);
    expect(statusView(null).known).toBe(false);
    expect(pickState({ progress: 7 }).progress).toBe(1);
    expect(pickState({}).progress).toBe(1);
  });

});

describe('manualGate: may motion controls be used, and why not', () => {
  const ok = { offline: false, conn: /** @type {const} */ ('connected'), commands: ['manual'], holdsLease: true };
  it('is open online, connected, granted, with the lease and a reachable controller', () => {
    expect(manualGate(ok)).toEqual({ ok: true, reason: '' });
    expect(manualGate({ ...ok, driver: pickState({ connected: true }) }).ok).toBe(true);
  });
  it('says why when it is closed, most fundamental first', () => {
    expect(manualGate({ ...ok, offline: true, commands: [] }).reason).toMatch(/Offline/);
    expect(manualGate({ ...ok, conn: 'disconnected', commands: [] }).reason).toBe('Not connected to ROS');
    expect(manualGate({ ...ok, commands: ['process'], holdsLease: false })).toEqual({ ok: false, reason: VIEW_ONLY_REASON });
    expect(VIEW_ONLY_REASON).toMatch(/role may not/i);
    expect(manualGate({ ...ok, holdsLease: false }).reason).toMatch(/Take control first/);
    expect(manualGate({ ...ok, busy: true }).reason).toMatch(/move is running/);
  });
  it('adds the controller being unreachable, with the driver\'s words', () => {
    const driver = pickState({ connected: false, controller: '10.0.0.2', message: 'robot controller at 10.0.0.2 is unreachable' });
    expect(manualGate({ ...ok, holdsLease: false, driver })).toEqual({ ok: false, reason: 'Robot controller at 10.0.0.2 is unreachable' });
    expect(manualGate({ ...ok, driver: pickState({ connected: false, controller: 'ur' }) }).reason).toBe('Robot controller at ur is unreachable');
  });
  it('knows when the page is not live', () => {
    expect(notLiveBecause({ offline: true, conn: 'connected', downSince: null })).toBe('offline');
    expect(notLiveBecause({ offline: false, conn: 'disconnected', downSince: 1 })).toBe('disconnected');
    expect(notLiveBecause({ offline: false, conn: 'connecting', downSince: null })).toBeNull();
    expect(notLiveBecause({ offline: false, conn: 'connected', downSince: null })).toBeNull();
  });
});

describe('why a jog ended', () => {
  it('says nothing when the user ended it, and why otherwise (a gate passes its own words)', () => {
    for (const own of ['released', 'key released', 'left the page', 'motion group changed', 'jog settings changed', 'Stop move', '']) {
      expect(jogStopNote(own)).toBe('');
    }
    expect(jogStopNote('pointer capture lost')).toBe('Jog stopped: the button lost the pointer');
    expect(jogStopNote('page hidden')).toBe('Jog stopped: the page went to the background');
    expect(jogStopNote('ROS link lost')).toBe('Jog stopped: the connection to the robot was lost');
    expect(jogStopNote('not sent: socket closed')).toBe('Jog stopped: the command could not be sent (socket closed)');
    expect(jogStopNote('Take control first')).toBe('Jog stopped: Take control first');
  });
});

describe('JogHold: hold-to-run', () => {
  afterEach(() => vi.useRealTimers());
  const msg = jogCommand({ group: 'arm', mode: 'joint', axis: 0, direction: 1, fraction: 0.5, frame: 'base' });

  function setup(o = {}) {
    vi.useFakeTimers();
    /** @type {any[]} */
    const sent = [];
    let allowed = true;
    let fail = false;
    /** @type {string[]} */
    const changes = [];
    const hold = new JogHold({
      publish: (m) => {
        if (fail) throw new Error('Not connected to ROS: the message was not sent');
        sent.push(m);
      },
      allowed: () => allowed,
      onChange: (m, why) => changes.push(m ? 'start' : `stop: ${why}`),
      ...o,
    });
    return {
      hold, sent, changes,
      /** the messages without their press number */
      plain: () => sent.map(({ press, ...m }) => m),
      /** @param {boolean} v */ setAllowed: (v) => (allowed = v),
      /** @param {boolean} v */ setFail: (v) => (fail = v),
      directions: () => sent.map((m) => m.direction),
    };
  }

  it('publishes at once and every 50 ms while held, then exactly one stop on release', () => {
    const t = setup();
    expect(t.hold.start(msg)).toBe(true);
    expect(t.plain()).toEqual([msg]);
    vi.advanceTimersByTime(JOG_PERIOD_MS - 1);
    expect(t.sent.length).toBe(1);
    vi.advanceTimersByTime(1);
    expect(t.sent.length).toBe(2);
    vi.advanceTimersByTime(4 * JOG_PERIOD_MS);
    expect(t.directions()).toEqual([1, 1, 1, 1, 1, 1]);
    expect(t.hold.active).toEqual({ ...msg, press: t.sent[0].press });

    expect(t.hold.stop()).toBe(true);
    expect(t.plain().at(-1)).toEqual({ ...msg, direction: 0 });
    // Release, pointercancel and lostpointercapture may all arrive: still one stop.
    expect(t.hold.stop('pointer cancelled')).toBe(false);
    expect(t.hold.stop('pointer capture lost')).toBe(false);
    vi.advanceTimersByTime(1000);
    expect(t.directions()).toEqual([1, 1, 1, 1, 1, 1, 0]);
    expect(t.hold.active).toBeNull();
    expect(t.changes).toEqual(['start', 'stop: released']);
  });

  it('stop without a jog sends nothing', () => {
    const t = setup();
    expect(t.hold.stop()).toBe(false);
    expect(t.sent).toEqual([]);
  });

  it('stops (one stop message) when the gate closes: lease lost, link down, page hidden', () => {
    const t = setup();
    t.hold.start(msg);
    vi.advanceTimersByTime(JOG_PERIOD_MS);
    t.setAllowed(false);
    vi.advanceTimersByTime(JOG_PERIOD_MS);
    expect(t.directions()).toEqual([1, 1, 0]);
    vi.advanceTimersByTime(1000);
    expect(t.directions()).toEqual([1, 1, 0]);
    expect(t.changes.at(-1)).toBe('stop: not allowed');
  });

  it('does not start while the gate is closed', () => {
    const t = setup();
    t.setAllowed(false);
    expect(t.hold.start(msg)).toBe(false);
    vi.advanceTimersByTime(1000);
    expect(t.sent).toEqual([]);
  });

  it('a refused publish ends the jog: nothing is retried or queued for later', () => {
    const t = setup();
    t.hold.start(msg);
    t.setFail(true);
    vi.advanceTimersByTime(JOG_PERIOD_MS);
    expect(t.hold.active).toBeNull();
    expect(t.changes.at(-1)).toMatch(/^stop: not sent: Not connected/);
    t.setFail(false);
    vi.advanceTimersByTime(1000);
    // The link is back: nothing that failed is sent late.
    expect(t.directions()).toEqual([1]);
  });

  it('a publish that fails at once does not leave a timer behind', () => {
    const t = setup();
    t.setFail(true);
    expect(t.hold.start(msg)).toBe(false);
    t.setFail(false);
    vi.advanceTimersByTime(1000);
    expect(t.sent).toEqual([]);
    expect(vi.getTimerCount()).toBe(0);
  });

  it('a second button replaces the running jog: one heartbeat, never two', () => {
    const t = setup();
    t.hold.start(msg);
    vi.advanceTimersByTime(20);
    const other = { ...msg, axis: 3, direction: /** @type {const} */ (-1) };
    t.hold.start(other);
    expect(t.plain().at(-1)).toEqual(other);
    expect(vi.getTimerCount()).toBe(1);
    vi.advanceTimersByTime(JOG_PERIOD_MS * 3);
    expect(t.sent.length).toBe(5);
    expect(t.sent.slice(1).every((m) => m.axis === 3)).toBe(true);
    t.hold.stop();
    expect(t.plain().at(-1)).toEqual({ ...other, direction: 0 });
    expect(vi.getTimerCount()).toBe(0);
  });

  it('each press has its own number: its heartbeats and its release carry it, the next press a new one', () => {
    const t = setup();
    t.hold.start(msg);
    vi.advanceTimersByTime(2 * JOG_PERIOD_MS);
    t.hold.stop();
    t.hold.start(msg);
    t.hold.stop();
    const [a, b] = [t.sent[0].press, t.sent[4].press];
    expect(t.sent.map((m) => m.press)).toEqual([a, a, a, a, b, b]);
    expect(Number.isInteger(a) && a > 0 && a <= 0xffffffff && b !== a).toBe(true);
    // Another page (or a reload) starts elsewhere: it does not repeat the numbers a driver may still hold.
    const other = setup();
    other.hold.start(msg);
    expect(other.sent[0].press).not.toBe(b);
  });

  it('ignores a start without a direction', () => {
    const t = setup();
    expect(t.hold.start({ ...msg, direction: 0 })).toBe(false);
    expect(t.sent).toEqual([]);
  });

  it('takes injected timers', () => {
    /** @type {(() => void)[]} */
    const fns = [];
    /** @type {any[]} */
    const sent = [];
    const hold = new JogHold({ publish: (m) => sent.push(m), setInterval: (fn) => fns.push(fn), clearInterval: () => fns.splice(0) });
    hold.start(msg);
    fns[0]();
    fns[0]();
    expect(sent.length).toBe(3);
    hold.stop();
    expect(fns.length).toBe(0);
    expect(sent.map((m) => m.direction)).toEqual([1, 1, 1, 0]);
  });
});
