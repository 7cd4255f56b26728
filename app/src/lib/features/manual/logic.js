/**
 * Manual motion's plain logic (no Svelte, no ROS): units, the driver's answers, service requests, what the
 * page shows, when its motion controls may be used, and the hold-to-run jog heartbeat.
 *
 * The ROS side speaks m, rad, s (the contract: /tmp spec "Manual motion", cell_msgs). The page speaks what a
 * UR pendant user reads: positions in mm, TCP rotations in rad (a rotation vector, as PolyScope shows it),
 * joints in degrees, relative rotations in degrees, speeds as a fraction of the driver's limits.
 */
import { commandGate } from '../../core/gate.js';
import { m } from '$lib/paraglide/messages.js';
import { cellText, fmtFixed } from '../../core/i18n.js';
import { paramsOf, saidText } from '../../core/said.js';

export const FEATURE_ID = 'manual';

/** ROS names of the driver (/cell/manual/...). Each motion group has its own state topic: stateTopic(group). */
export const NAMES = Object.freeze({
  jog: { topic: '/cell/manual/jog', type: 'cell_msgs/JogCommand' },
  groups: { service: '/cell/manual/groups', type: 'cell_msgs/GetMotionGroups' },
  getPose: { service: '/cell/manual/get_pose', type: 'cell_msgs/GetPose' },
  moveNamed: { service: '/cell/manual/move_named', type: 'cell_msgs/MoveNamed' },
  moveRelative: { service: '/cell/manual/move_relative', type: 'cell_msgs/MoveRelative' },
  movePose: { service: '/cell/manual/move_pose', type: 'cell_msgs/MovePose' },
  tool: { service: '/cell/manual/tool', type: 'cell_msgs/ToolAction' },
  stop: { service: '/cell/manual/stop', type: 'std_srvs/Trigger' },
});

/** cell_msgs/RobotState of one motion group, 20 Hz. @param {string} group */
export const stateTopic = (group) => `/cell/manual/${group}/state`;
export const STATE_TYPE = 'cell_msgs/RobotState';

/** The jog heartbeat: the driver stops ~200 ms after the last JogCommand, so 50 ms leaves room for 3 misses. */
export const JOG_PERIOD_MS = 50;
/** The state topic comes at 20 Hz: older than this and it is stale. */
export const STATE_STALE_MS = 1000;
/** ISO 10218-1 reduced speed: manual TCP speed never above 250 mm/s (the driver clamps to it too). */
export const MAX_MANUAL_TCP_SPEED = 0.25;
/** Slider floor: a 0 would mean "the driver's default" in the move services, not "slow". */
export const MIN_FRACTION = 0.01;
/** Service moves block until the arm arrives: wait long, "Stop move" ends them sooner. */
export const MOVE_TIMEOUT_MS = 180_000;

export const CART_AXES = /** @type {const} */ (['X', 'Y', 'Z', 'RX', 'RY', 'RZ']);

// ---- units ----

/** @param {number} mm */
export const mmToM = (mm) => mm / 1000;
/** @param {number} m */
export const mToMm = (m) => m * 1000;
/** @param {number} deg */
export const degToRad = (deg) => (deg * Math.PI) / 180;
/** @param {number} rad */
export const radToDeg = (rad) => (rad * 180) / Math.PI;

/** @param {number} v @param {number} lo @param {number} hi */
export const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));

/**
 * A number typed on a shop-floor keyboard: "12.5", "-3", "1,5" (decimal comma), surrounding spaces.
 * @param {unknown} text
 * @returns {number | null}  null when empty or not a finite number
 */
export function parseNumber(text) {
  if (typeof text === 'number') return Number.isFinite(text) ? text : null;
  if (typeof text !== 'string') return null;
  // (A decimal comma, and the minus sign U+2212 some locales write, as the page shows numbers in the user's locale.)
  const t = text.trim().replace(',', '.').replace(/^\u2212/, '-');
  if (t === '' || !/^[-+]?(\d+\.?\d*|\.\d+)(e[-+]?\d+)?$/i.test(t)) return null;
  const v = Number(t);
  return Number.isFinite(v) ? v : null;
}

/**
 * A number with `digits` decimals in the user's locale ("12.50", "12,50").
 * @param {unknown} v @param {number} digits
 * @returns {string}  '—' for anything that is not a finite number; never "-0.0"
 */
export function fixed(v, digits) {
  if (typeof v !== 'number' || !Number.isFinite(v)) return '—';
  const s = fmtFixed(v, digits);
  return /^[-\u2212]/.test(s) && !/[1-9]/.test(s) ? s.slice(1) : s;
}

// ---- the driver's answer to /cell/manual/groups ----

/**
 * @typedef {object} Limits  the driver's manual limits (ManualLimits), SI units
 * @property {number} defaultSpeed         rad/s
 * @property {number} defaultAcceleration  rad/s^2
 * @property {number} maxSpeed             rad/s (joint moves, joint jog, Cartesian rotation jog)
 * @property {number} maxAcceleration      rad/s^2
 * @property {number} maxTcpSpeed          m/s, never above 0.25
 * @property {number} maxTcpAcceleration   m/s^2
 * @property {number} jogTimeout           s
 */
/** @typedef {{ name: string, positions: number[] }} NamedConfiguration */
/** @typedef {{ name: string, joints: string[], configurations: NamedConfiguration[] }} MotionGroup */
/** @typedef {{ name: string, actions: string[], group: string }} ToolInfo  group '' = the first group */
/** @typedef {{ groups: MotionGroup[], tools: ToolInfo[], limits: Limits }} DriverSetup */

/** @param {unknown} v */
const num = (v) => (typeof v === 'number' && Number.isFinite(v) && v > 0 ? v : 0);
/** @param {unknown} v @returns {string[]} */
const strings = (v) => (Array.isArray(v) ? v.filter((s) => typeof s === 'string') : []);

/** @param {any} l @returns {Limits} */
export function normalizeLimits(l) {
  const maxTcp = num(l?.max_tcp_speed);
  return {
    defaultSpeed: num(l?.default_speed),
    defaultAcceleration: num(l?.default_acceleration),
    maxSpeed: num(l?.max_speed),
    maxAcceleration: num(l?.max_acceleration),
    // The cap holds whatever the driver says (ISO 10218-1 reduced speed).
    maxTcpSpeed: maxTcp ? Math.min(maxTcp, MAX_MANUAL_TCP_SPEED) : MAX_MANUAL_TCP_SPEED,
    maxTcpAcceleration: num(l?.max_tcp_acceleration),
    jogTimeout: num(l?.jog_timeout),
  };
}

/**
 * cell_msgs/GetMotionGroups response -> what the page uses (unnamed entries dropped).
 * @param {any} resp
 * @returns {DriverSetup}
 */
export function normalizeSetup(resp) {
  const groups = (Array.isArray(resp?.groups) ? resp.groups : [])
    .filter((/** @type {any} */ g) => typeof g?.name === 'string' && g.name)
    .map((/** @type {any} */ g) => ({
      name: g.name,
      joints: strings(g.joints),
      configurations: (Array.isArray(g.configurations) ? g.configurations : [])
        .filter((/** @type {any} */ c) => typeof c?.name === 'string' && c.name)
        .map((/** @type {any} */ c) => ({ name: c.name, positions: Array.isArray(c.positions) ? c.positions.map(Number) : [] })),
    }));
  const tools = (Array.isArray(resp?.tools) ? resp.tools : [])
    .filter((/** @type {any} */ t) => typeof t?.name === 'string' && t.name)
    .map((/** @type {any} */ t) => ({ name: t.name, actions: strings(t.actions), group: typeof t.group === 'string' ? t.group : '' }));
  return { groups, tools, limits: normalizeLimits(resp?.limits) };
}

// ---- motion groups ----

/**
 * The motion groups of the cell file's manual section (/api/config `features.manual`), as the driver reports
 * them: known before the driver answers (the state topic of the chosen group, the joint names).
 * @param {any} section
 * @returns {MotionGroup[]}
 */
export function sectionGroups(section) {
  return (Array.isArray(section?.groups) ? section.groups : [])
    .filter((/** @type {any} */ g) => typeof g?.name === 'string' && g.name)
    .map((/** @type {any} */ g) => ({
      name: g.name,
      joints: strings(g.joints),
      configurations: Object.entries(g.configurations && typeof g.configurations === 'object' ? g.configurations : {})
        .map(([name, positions]) => ({ name, positions: Array.isArray(positions) ? positions.map(Number) : [] })),
    }));
}

/**
 * The group names the page offers: the driver's (what commands go to) once it answered, else the cell file's.
 * @param {DriverSetup | null} setup @param {MotionGroup[]} fromSection
 * @returns {string[]}
 */
export function groupChoices(setup, fromSection) {
  const list = setup?.groups.length ? setup.groups : fromSection;
  return list.map((g) => g.name);
}

/**
 * The group shown: the remembered choice while it is one of the groups, else the first.
 * @param {string[]} names @param {string | null | undefined} remembered
 */
export function chosenGroup(names, remembered) {
  return remembered && names.includes(remembered) ? remembered : (names[0] ?? '');
}

/**
 * The tools of one group. A tool's group: the driver's answer (ToolInfo.group), else the cell file's
 * (manual.tools[].group), else the first group.
 * @param {ToolInfo[]} tools @param {string} group @param {string} firstGroup
 * @param {any} [section] the cell file's manual section
 * @returns {ToolInfo[]}
 */
export function toolsOfGroup(tools, group, firstGroup, section = null) {
  const fromCell = (/** @type {string} */ name) => {
    const t = Array.isArray(section?.tools) ? section.tools.find((/** @type {any} */ x) => x?.name === name) : null;
    return typeof t?.group === 'string' ? t.group : '';
  };
  return tools.filter((t) => (t.group || fromCell(t.name) || firstGroup) === group);
}

// ---- names ----

/** "gripper" -> "Gripper", "tool_changer" -> "Tool changer". @param {string} s */
export function humanize(s) {
  const t = String(s ?? '').replace(/[_-]+/g, ' ').trim();
  return t ? t[0].toUpperCase() + t.slice(1) : '';
}

/**
 * The tool button's name: the cell file's title of the action in the user's language (manual.tools[].actions[].title),
 * else "Gripper open" from the names.
 * @param {string} tool @param {string} action @param {any} [section]  the cell file's manual section
 */
export function toolLabel(tool, action, section) {
  const tools = Array.isArray(section?.tools) ? section.tools : [];
  const actions = tools.find((/** @type {any} */ t) => t?.name === tool)?.actions;
  const title = Array.isArray(actions) ? actions.find((/** @type {any} */ a) => a?.name === action)?.title : undefined;
  return (title && cellText(title)) || `${humanize(tool)} ${String(action ?? '').replace(/[_-]+/g, ' ')}`.trim();
}

/**
 * The jog button's accessible name: "Jog joint 1 +" (1-based) or "Jog X -".
 * @param {'joint' | 'cartesian'} mode @param {number} axis  0-based @param {1 | -1} direction
 */
export function jogLabel(mode, axis, direction) {
  if (mode === 'joint') {
    const joint = String(axis + 1);
    return direction > 0 ? m.manual_jog_joint_plus({ joint }) : m.manual_jog_joint_minus({ joint });
  }
  const name = CART_AXES[axis];
  return direction > 0 ? m.manual_jog_axis_plus({ axis: name }) : m.manual_jog_axis_minus({ axis: name });
}

/**
 * The rows of the jog pad: one per joint of the group (joint mode) or per Cartesian axis.
 * @param {'joint' | 'cartesian'} mode
 * @param {string[]} joints  the group's joint names
 * @returns {{ axis: number, name: string, detail: string }[]}
 */
export function jogRows(mode, joints) {
  if (mode === 'cartesian') {
    return CART_AXES.map((a, axis) => ({ axis, name: a, detail: axis < 3 ? 'mm' : 'rad' }));
  }
  return joints.map((j, axis) => ({ axis, name: `J${axis + 1}`, detail: jointShortName(j) }));
}

/** The UR joint names: a cell file's joint name ends with one of them ("left_shoulder_pan_joint"). */
export const UR_JOINTS = Object.freeze(['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint']);

/**
 * "shoulder_pan_joint" -> "shoulder pan"; "left_shoulder_pan_joint" -> "shoulder pan" (the group is shown already).
 * @param {string} name
 */
export function jointShortName(name) {
  const n = String(name ?? '');
  const ur = UR_JOINTS.find((j) => n === j || n.endsWith(`_${j}`));
  return (ur ?? n).replace(/_joint$/, '').replace(/_/g, ' ');
}

// ---- speeds ----

/**
 * The fraction a speed slider starts at: the driver's default over its maximum.
 * @param {number} def @param {number} max @param {number} [fallback]
 */
export function defaultFraction(def, max, fallback = 0.25) {
  if (!(max > 0) || !(def > 0)) return fallback;
  return clamp(def / max, MIN_FRACTION, 1);
}

/**
 * What a jog at `fraction` of the manual maximum runs at (the driver's rule).
 * @param {number} fraction @param {Limits} limits
 * @returns {{ mmPerS: number, radPerS: number }}  TCP linear speed, joint / TCP rotation speed
 */
export function jogRates(fraction, limits) {
  const f = clamp(fraction, 0, 1);
  return { mmPerS: mToMm(f * limits.maxTcpSpeed), radPerS: f * limits.maxSpeed };
}

/**
 * Speed and acceleration of a service move at the slider fractions: joint moves in rad/s and rad/s^2,
 * Cartesian moves in m/s and m/s^2. A limit the driver did not report gives 0 (= the driver's default).
 * @param {number} speedFraction @param {number} accFraction @param {Limits} limits
 */
export function moveRates(speedFraction, accFraction, limits) {
  const s = clamp(speedFraction, MIN_FRACTION, 1);
  const a = clamp(accFraction, MIN_FRACTION, 1);
  return {
    joint: { speed: s * limits.maxSpeed, acceleration: a * limits.maxAcceleration },
    tcp: { speed: s * limits.maxTcpSpeed, acceleration: a * limits.maxTcpAcceleration },
  };
}

// ---- messages and requests ----

/**
 * cell_msgs/JogCommand.
 * @param {{ group: string, mode: 'joint' | 'cartesian', axis: number, direction: number, fraction: number, frame: 'base' | 'tool' }} o
 */
export function jogCommand({ group, mode, axis, direction, fraction, frame }) {
  return {
    group,
    mode,
    axis: Math.max(0, Math.trunc(axis)),
    direction: direction > 0 ? 1 : direction < 0 ? -1 : 0,
    speed: clamp(fraction, MIN_FRACTION, 1),
    frame: frame === 'tool' ? 'tool' : 'base',
  };
}

/** @typedef {{ ok: true, request: any } | { ok: false, error: string }} Built */

/**
 * cell_msgs/MoveNamed request.
 * @param {string} group @param {string} name @param {{ speed: number, acceleration: number }} rates  rad/s, rad/s^2
 * @returns {Built}
 */
export function namedRequest(group, name, rates) {
  if (!group) return { ok: false, error: m.manual_choose_group() };
  if (!name) return { ok: false, error: m.manual_choose_configuration() };
  return { ok: true, request: { group, name, speed: rates.speed, acceleration: rates.acceleration } };
}

/** @typedef {{ dx: string, dy: string, dz: string, drx: string, dry: string, drz: string }} RelativeForm  mm and degrees */
/** @typedef {{ x: string, y: string, z: string, rx: string, ry: string, rz: string }} PoseForm  mm and rad */

/**
 * cell_msgs/MoveRelative request from the form (dx, dy, dz in mm; drx, dry, drz in degrees, a rotation
 * vector, as a UR pose offset). Empty fields count as 0; an all-zero offset is refused (nothing to do).
 * @param {string} group @param {RelativeForm} form @param {'base' | 'tool'} frame
 * @param {{ speed: number, acceleration: number }} rates  m/s, m/s^2
 * @returns {Built}
 */
export function relativeRequest(group, form, frame, rates) {
  if (!group) return { ok: false, error: m.manual_choose_group() };
  const keys = /** @type {const} */ (['dx', 'dy', 'dz', 'drx', 'dry', 'drz']);
  /** @type {number[]} */
  const v = [];
  for (const k of keys) {
    const raw = form[k];
    const n = raw === undefined || String(raw).trim() === '' ? 0 : parseNumber(raw);
    if (n === null) return { ok: false, error: m.manual_field_not_number({ field: k }) };
    v.push(n);
  }
  if (v.every((n) => n === 0)) return { ok: false, error: m.manual_offset_empty() };
  const offset = [mmToM(v[0]), mmToM(v[1]), mmToM(v[2]), degToRad(v[3]), degToRad(v[4]), degToRad(v[5])];
  return { ok: true, request: { group, offset, frame: frame === 'tool' ? 'tool' : 'base', speed: rates.speed, acceleration: rates.acceleration } };
}

/**
 * cell_msgs/MovePose request from the form (x, y, z in mm; rx, ry, rz in rad, base frame). Every field is needed.
 * @param {string} group @param {PoseForm} form @param {{ speed: number, acceleration: number }} rates  m/s, m/s^2
 * @returns {Built}
 */
export function poseRequest(group, form, rates) {
  if (!group) return { ok: false, error: m.manual_choose_group() };
  const keys = /** @type {const} */ (['x', 'y', 'z', 'rx', 'ry', 'rz']);
  /** @type {number[]} */
  const v = [];
  for (const k of keys) {
    const n = parseNumber(form[k]);
    if (n === null) return { ok: false, error: m.manual_pose_field_missing({ field: k }) };
    v.push(n);
  }
  const pose = [mmToM(v[0]), mmToM(v[1]), mmToM(v[2]), v[3], v[4], v[5]];
  return { ok: true, request: { group, pose, speed: rates.speed, acceleration: rates.acceleration } };
}

/**
 * The absolute-pose form filled from a TCP pose (m, rotation vector rad).
 * @param {unknown} tcpPose
 * @returns {PoseForm | null}
 */
export function poseToForm(tcpPose) {
  if (!isPose(tcpPose)) return null;
  const p = /** @type {number[]} */ (tcpPose);
  return { x: fixed(mToMm(p[0]), 2), y: fixed(mToMm(p[1]), 2), z: fixed(mToMm(p[2]), 2), rx: fixed(p[3], 4), ry: fixed(p[4], 4), rz: fixed(p[5], 4) };
}

/** @param {unknown} p @returns {boolean} */
export function isPose(p) {
  return Array.isArray(p) && p.length >= 6 && p.slice(0, 6).every((v) => typeof v === 'number' && Number.isFinite(v));
}

// ---- what the page shows ----

/**
 * The TCP pose as the pendant shows it: X, Y, Z in mm and RX, RY, RZ in rad (a rotation vector, no quaternion).
 * @param {unknown} tcpPose
 * @returns {{ label: string, value: string, unit: string }[]}
 */
export function poseRows(tcpPose) {
  const p = isPose(tcpPose) ? /** @type {number[]} */ (tcpPose) : null;
  return CART_AXES.map((label, i) => ({
    label,
    value: p ? (i < 3 ? fixed(mToMm(p[i]), 1) : fixed(p[i], 4)) : '—',
    unit: i < 3 ? 'mm' : 'rad',
  }));
}

/**
 * Joint positions in degrees, named after the group's joints when they match.
 * @param {unknown} positions  rad
 * @param {string[]} [names]
 * @returns {{ label: string, name: string, value: string }[]}
 */
export function jointRows(positions, names = []) {
  const q = Array.isArray(positions) ? positions : [];
  const n = Math.max(q.length, names.length);
  return Array.from({ length: n }, (_, i) => ({
    label: `J${i + 1}`,
    name: names[i] ? jointShortName(names[i]) : '',
    value: typeof q[i] === 'number' ? fixed(radToDeg(q[i]), 2) : '—',
  }));
}

/** @typedef {'ok' | 'warn' | 'danger' | 'neutral' | 'info'} Tone */

/** "POWER_OFF" -> "Power off": a UR robot or safety mode in words (an unknown one as written, humanized). @param {string} s */
export function modeText(s) {
  if (!s) return m.manual_state_unknown();
  switch (s) {
    // Robot modes
    case 'NO_CONTROLLER': return m.manual_mode_no_controller();
    case 'DISCONNECTED': return m.manual_mode_disconnected();
    case 'CONFIRM_SAFETY': return m.manual_mode_confirm_safety();
    case 'BOOTING': return m.manual_mode_booting();
    case 'POWER_OFF': return m.manual_mode_power_off();
    case 'POWER_ON': return m.manual_mode_power_on();
    case 'IDLE': return m.manual_mode_idle();
    case 'BACKDRIVE': return m.manual_mode_backdrive();
    case 'RUNNING': return m.manual_mode_running();
    case 'UPDATING_FIRMWARE': return m.manual_mode_updating_firmware();
    case 'CONTROLLER_NOT_RUNNING': return m.manual_mode_controller_not_running();
    // Safety modes
    case 'NORMAL': return m.manual_safety_normal();
    case 'REDUCED': return m.manual_safety_reduced();
    case 'PROTECTIVE_STOP': return m.manual_safety_protective_stop();
    case 'RECOVERY': return m.manual_safety_recovery();
    case 'SAFEGUARD_STOP': return m.manual_safety_safeguard_stop();
    case 'SYSTEM_EMERGENCY_STOP': return m.manual_safety_system_emergency_stop();
    case 'ROBOT_EMERGENCY_STOP': return m.manual_safety_robot_emergency_stop();
    case 'VIOLATION': return m.manual_safety_violation();
    case 'FAULT': return m.manual_safety_fault();
    case 'VALIDATE_JOINT_ID': return m.manual_safety_validate_joint_id();
    case 'UNDEFINED_SAFETY_MODE': return m.manual_safety_undefined();
    case 'AUTOMATIC_MODE_SAFEGUARD_STOP': return m.manual_safety_automatic_mode_safeguard_stop();
    case 'SYSTEM_THREE_POSITION_ENABLING_STOP': return m.manual_safety_three_position_enabling_stop();
  }
  const t = s.toLowerCase().replace(/_/g, ' ');
  return t[0].toUpperCase() + t.slice(1);
}

/** @param {string} mode  UR robot mode name @returns {Tone} */
export function robotModeTone(mode) {
  if (mode === 'RUNNING') return 'ok';
  if (['IDLE', 'POWER_ON', 'BOOTING', 'POWER_OFF', 'BACKDRIVE', 'CONFIRM_SAFETY', 'UPDATING_FIRMWARE'].includes(mode)) return 'warn';
  if (!mode) return 'neutral';
  return 'danger';
}

/** @param {string} mode  UR safety mode name @returns {Tone} */
export function safetyTone(mode) {
  if (mode === 'NORMAL') return 'ok';
  if (mode === 'REDUCED' || mode === 'RECOVERY') return 'warn';
  if (!mode) return 'neutral';
  return 'danger';
}

/**
 * @typedef {object} RobotState  cell_msgs/RobotState as received (the fields the page uses)
 * @property {boolean} connected
 * @property {string} controller
 * @property {string} robot_mode
 * @property {string} safety_mode
 * @property {number} speed_scaling
 * @property {boolean} program_running
 * @property {string} motion
 * @property {string} motion_group
 * @property {string} motion_target
 * @property {number} progress
 * @property {string} message
 * @property {number[]} joint_positions
 * @property {number[]} tcp_pose
 * @property {number[]} tcp_speed
 */

/**
 * Keep only the fields the page shows (what is stored as the last known state).
 * @param {any} msg
 * @returns {RobotState}
 */
export function pickState(msg) {
  const nums = (/** @type {any} */ a) => (Array.isArray(a) ? a.map(Number) : []);
  const str = (/** @type {any} */ s) => (typeof s === 'string' ? s : '');
  return {
    connected: msg?.connected === true,
    controller: str(msg?.controller),
    robot_mode: str(msg?.robot_mode),
    safety_mode: str(msg?.safety_mode),
    speed_scaling: typeof msg?.speed_scaling === 'number' ? msg.speed_scaling : 0,
    program_running: msg?.program_running === true,
    motion: str(msg?.motion) || 'idle',
    motion_group: str(msg?.motion_group),
    motion_target: str(msg?.motion_target),
    progress: typeof msg?.progress === 'number' ? clamp(msg.progress, 0, 1) : 1,
    message: saidText(str(msg?.message_code), paramsOf(msg?.message_params), str(msg?.message)),
    joint_positions: nums(msg?.joint_positions),
    tcp_pose: nums(msg?.tcp_pose),
    tcp_speed: nums(msg?.tcp_speed),
  };
}

/**
 * The status strip, in words (colour is never the only signal).
 * @param {RobotState | null} s
 */
export function statusView(s) {
  if (!s) {
    return {
      known: false,
      driver: { text: m.manual_state_none(), tone: /** @type {Tone} */ ('neutral') },
      robot: { text: m.manual_state_unknown(), tone: /** @type {Tone} */ ('neutral') },
      safety: { text: m.manual_state_unknown(), tone: /** @type {Tone} */ ('neutral') },
      motion: { text: m.manual_state_unknown(), moving: false, progress: 1 },
      message: '',
    };
  }
  const moving = s.motion !== 'idle' && s.motion !== '';
  const target = s.motion_target;
  const group = s.motion_group;
  const motionText = !moving
    ? m.manual_motion_idle()
    : s.motion === 'moving'
      ? (target ? m.manual_motion_moving_to({ target }) : m.manual_motion_moving())
      : s.motion === 'tool'
        ? (target ? m.manual_motion_tool_target({ target }) : m.manual_motion_tool())
        : s.motion === 'jogging'
          ? (group ? m.manual_motion_jogging_group({ group }) : m.manual_motion_jogging())
          : s.motion === 'stopping'
            ? m.manual_motion_stopping()
            : s.motion;
  const controller = s.controller;
  return {
    known: true,
    driver: s.connected
      ? { text: controller ? m.manual_driver_connected_to({ controller }) : m.manual_driver_connected(), tone: /** @type {Tone} */ ('ok') }
      : { text: controller ? m.manual_driver_unreachable_at({ controller }) : m.manual_driver_unreachable(), tone: /** @type {Tone} */ ('danger') },
    robot: { text: s.connected ? modeText(s.robot_mode) : m.manual_state_unknown(), tone: s.connected ? robotModeTone(s.robot_mode) : /** @type {Tone} */ ('neutral') },
    safety: { text: s.connected ? modeText(s.safety_mode) : m.manual_state_unknown(), tone: s.connected ? safetyTone(s.safety_mode) : /** @type {Tone} */ ('neutral') },
    motion: { text: motionText, moving, progress: s.progress },
    message: s.message,
  };
}

/** "robot controller at 10.0.0.2 is unreachable" -> "Robot controller at 10.0.0.2 is unreachable". @param {string} s */
const sentence = (s) => (s ? s[0].toUpperCase() + s.slice(1) : s);

/**
 * The manual page's wording for a role without the command grant (the e2e tests look for "role may not").
 * (In the language of the page: a change of language reloads it.)
 */
export const VIEW_ONLY_REASON = m.manual_view_only();

/**
 * May the page's motion controls (jog, moves, tool actions) be used now, and if not, why (in words).
 * Order: what the user cannot fix here first (offline, ROS down, the role), then the robot controller,
 * then the lease (which the user can take).
 * @param {object} o
 * @param {boolean} o.offline
 * @param {'connecting' | 'connected' | 'disconnected'} o.conn
 * @param {string[] | undefined} o.commands  /api/config `commands`
 * @param {boolean} o.holdsLease
 * @param {RobotState | null} [o.driver]  the live driver state (null: none yet, not checked)
 * @param {boolean} [o.busy]  a move from this page is running
 * @returns {import('../../core/gate.js').Gate}
 */
export function manualGate({ offline, conn, commands, holdsLease, driver = null, busy = false }) {
  const link = commandGate({ offline, conn });
  if (!link.ok) return link;
  if (Array.isArray(commands) && !commands.includes(FEATURE_ID)) return { ok: false, reason: m.manual_view_only() };
  if (driver && !driver.connected) {
    const controller = driver.controller;
    return { ok: false, reason: sentence(driver.message) || (controller ? m.manual_controller_unreachable_at({ controller }) : m.manual_controller_unreachable()) };
  }
  const lease = commandGate({ offline: false, needsLease: true, holdsLease });
  if (!lease.ok) return lease;
  if (busy) return { ok: false, reason: m.manual_move_running() };
  return { ok: true, reason: '' };
}

/**
 * Why the page does not show live data, if it does not.
 * @param {{ offline: boolean, conn: 'connecting' | 'connected' | 'disconnected', downSince: number | null }} o
 * @returns {'offline' | 'disconnected' | null}
 */
export function notLiveBecause({ offline, conn, downSince }) {
  if (offline) return 'offline';
  if (conn !== 'connected' && (conn === 'disconnected' || downSince !== null)) return 'disconnected';
  return null;
}

// ---- hold-to-run ----

/**
 * @typedef {ReturnType<typeof jogCommand>} JogMsg
 */

// Why JogHold stopped, as the page and the pad pass it (a closed gate passes its own reason, already in the
// user's language). The user's own ends need no word; the others end a jog while the thumb may still be down.
const OWN_JOG_ENDS = new Set(['released', 'key released', 'left the page', 'motion group changed', 'jog settings changed', 'Stop move']);
/** @type {Record<string, () => string>} */
const JOG_END_SAID = {
  'pointer cancelled': () => m.manual_jog_note_cancelled(),
  'pointer capture lost': () => m.manual_jog_note_capture(),
  'focus left the button': () => m.manual_jog_note_blur(),
  'window lost focus': () => m.manual_jog_note_window(),
  'page hidden': () => m.manual_jog_note_hidden(),
  'ROS link lost': () => m.manual_jog_note_link(),
};
const NOT_SENT = 'not sent: ';

/**
 * What the jog pad says after a jog ended that the user did not end ('' when they did): the arm stopped while the
 * button may still be held, and only a new press moves it again.
 * @param {string} reason  JogHold's stop reason
 * @returns {string}
 */
export function jogStopNote(reason) {
  if (!reason || OWN_JOG_ENDS.has(reason)) return '';
  const why = JOG_END_SAID[reason]?.()
    ?? (reason.startsWith(NOT_SENT) ? m.manual_jog_note_not_sent({ error: reason.slice(NOT_SENT.length) }) : reason);
  return m.manual_jog_note_stopped({ why });
}

/**
 * Hold-to-run jogging: while a jog button is held, the same JogCommand goes out at once and then every
 * JOG_PERIOD_MS; on release (or any stop condition) one command with direction 0 goes out and nothing after
 * it. The driver stops on its own ~200 ms after the last command, so a lost release is still safe.
 * Never queues: each tick sends the current command once; a publish that throws (not connected, refused)
 * ends the jog. Pressing another jog button replaces the running jog (the driver does the same).
 * Each press carries its own number (`press`): a jog the driver stopped (Stop robot, a take-over, the
 * controller) stays stopped while the same press goes on; only a new press moves the arm again.
 * The numbers start at a random value, so a reloaded page never repeats one the driver still holds.
 */
export class JogHold {
  /** @type {(JogMsg & { press: number }) | null} */
  #msg = null;
  #press = 1 + Math.floor(Math.random() * 0x7fffffff);
  /** @type {any} */
  #timer = null;

  /**
   * @param {object} o
   * @param {(msg: JogMsg) => void} o.publish  throws when the message cannot be sent
   * @param {() => boolean} [o.allowed]  checked before every send: false ends the jog (gate closed)
   * @param {number} [o.periodMs]
   * @param {(fn: () => void, ms: number) => any} [o.setInterval]
   * @param {(t: any) => void} [o.clearInterval]
   * @param {(active: JogMsg | null, reason: string) => void} [o.onChange]  the running jog changed
   */
  constructor(o) {
    this.publish = o.publish;
    this.allowed = o.allowed ?? (() => true);
    this.periodMs = o.periodMs ?? JOG_PERIOD_MS;
    this.setInterval = o.setInterval ?? ((fn, ms) => setInterval(fn, ms));
    this.clearInterval = o.clearInterval ?? ((t) => clearInterval(t));
    this.onChange = o.onChange ?? (() => {});
  }

  /** The running jog, if any. */
  get active() {
    return this.#msg;
  }

  /**
   * Start (or replace) a jog: publishes at once, then every period until stop().
   * @param {JogMsg} msg  direction +1 or -1
   * @returns {boolean}  whether the jog is running
   */
  start(msg) {
    if (!msg || (msg.direction !== 1 && msg.direction !== -1)) return false;
    if (!this.allowed()) {
      this.stop('not allowed');
      return false;
    }
    this.#press = (this.#press % 0xffffffff) + 1; // uint32, never 0 (0: a publisher without press numbers)
    this.#msg = { ...msg, press: this.#press };
    this.#clearTimer();
    if (!this.#send()) return false;
    this.#timer = this.setInterval(() => this.#tick(), this.periodMs);
    this.onChange(msg, 'started');
    return true;
  }

  /**
   * End the jog: one command with direction 0, then nothing. Safe to call any number of times.
   * @param {string} [reason]
   * @returns {boolean}  whether a jog was running
   */
  stop(reason = 'released') {
    const running = this.#msg;
    this.#clearTimer();
    if (!running) return false;
    this.#msg = null;
    try {
      this.publish({ ...running, direction: 0 });
    } catch {
      // Not connected or refused: the driver's timeout stops the arm.
    }
    this.onChange(null, reason);
    return true;
  }

  #tick() {
    if (!this.#msg) return this.#clearTimer();
    if (!this.allowed()) return void this.stop('not allowed');
    this.#send();
  }

  /** @returns {boolean} */
  #send() {
    const running = this.#msg;
    if (!running) return false;
    try {
      this.publish(running);
      return true;
    } catch (e) {
      this.stop(`${NOT_SENT}${e instanceof Error ? e.message : String(e)}`);
      return false;
    }
  }

  #clearTimer() {
    if (this.#timer !== null) this.clearInterval(this.#timer);
    this.#timer = null;
  }
}
