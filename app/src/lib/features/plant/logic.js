/**
 * The plant feature's plain logic (no Svelte): the API, reading its answer defensively, the order of the cells and
 * every text a cell card or the header shows. Tests import it directly.
 *
 * API (bff/src/features/plant): GET /api/plant/cells -> { broker, cells } (see PlantData);
 * GET /api/plant/events -> Server-Sent Events, `event: cells` with the same JSON on connect and after every change.
 */
import { m } from '$lib/paraglide/messages.js';
import { request } from '../../core/api.js';
import { fmtDateTime, fmtFixed, fmtNumber, getLocale } from '../../core/i18n.js';

export const FEATURE_ID = 'plant';

/** Where the live feed is (an EventSource URL, same origin). */
export const EVENTS_URL = '/api/plant/events';

export const plantApi = {
  cells: () => request('GET', '/api/plant/cells'),
};

/** @typedef {{ group: string, connected: boolean, mode: string }} PlantRobot */
/** @typedef {{ name: string, state: string }} PlantModule */
/**
 * One robot cell as the plant's broker last heard of it.
 * @typedef {object} PlantCell
 * @property {string} id  "group/node"
 * @property {string} group
 * @property {string} node
 * @property {string} name  '' if the cell never sent its birth name
 * @property {string} url  the cell's own UI, '' if none
 * @property {boolean} online
 * @property {number} since  online since / offline since (ms since the epoch)
 * @property {boolean} ros  the cell's BFF reaches its ROS side
 * @property {string} mode
 * @property {string} safety
 * @property {number} alarms
 * @property {string} alarm  the most severe active alarm's text
 * @property {number} severity  -1 none, 0 info, 1 warning, 2 error
 * @property {string} process
 * @property {string} operation
 * @property {number} cycles
 * @property {number} last_cycle_s  0: none
 * @property {PlantRobot[]} robots
 * @property {PlantModule[]} modules
 * @property {number} updated  ms since the epoch of its last message
 * @property {PlantShift | null} shift  what the plant view counted of its shift (null: the server sent none)
 */
/**
 * @typedef {{ cycles_last_hour: number, running_share: number | null, observed_s: number }} PlantShift
 *   cycles completed in the last hour; the share of the shift (8 h, or since the view first heard of the cell) in
 *   operation mode "running", null before any time passed
 */
/** @typedef {{ state: 'connected' | 'connecting' | 'down' | 'off' | string, since: number, error: string }} PlantBroker */
/** @typedef {{ broker: PlantBroker, cells: PlantCell[] }} PlantData */
/** @typedef {'alarm' | 'offline' | 'ok'} CellStatusKind */

// ---- reading the answer ----

/** @param {any} v */
const str = (v) => (typeof v === 'string' ? v : '');
/** @param {any} v @param {number} [d] */
const num = (v, d = 0) => (typeof v === 'number' && Number.isFinite(v) ? v : d);
/** @param {any} v */
const arr = (v) => (Array.isArray(v) ? v : []);

/** @param {any} c @returns {PlantCell} */
export function readCell(c) {
  c = c && typeof c === 'object' ? c : {};
  const group = str(c.group);
  const node = str(c.node);
  return {
    id: str(c.id) || (group && node ? `${group}/${node}` : node),
    group,
    node,
    name: str(c.name),
    url: str(c.url),
    online: c.online === true,
    since: num(c.since),
    ros: c.ros !== false,
    mode: str(c.mode),
    safety: str(c.safety),
    alarms: Math.max(0, num(c.alarms)),
    alarm: str(c.alarm),
    severity: num(c.severity, -1),
    process: str(c.process),
    operation: str(c.operation),
    cycles: Math.max(0, num(c.cycles)),
    last_cycle_s: num(c.last_cycle_s),
    robots: arr(c.robots).map((r) => ({ group: str(r?.group), connected: r?.connected === true, mode: str(r?.mode) })),
    modules: arr(c.modules).map((m) => ({ name: str(m?.name), state: str(m?.state) })),
    updated: num(c.updated),
    shift: c.shift && typeof c.shift === 'object' ? {
      cycles_last_hour: Math.max(0, num(c.shift.cycles_last_hour)),
      running_share: typeof c.shift.running_share === 'number' && Number.isFinite(c.shift.running_share) ? Math.min(1, Math.max(0, c.shift.running_share)) : null,
      observed_s: Math.max(0, num(c.shift.observed_s)),
    } : null,
  };
}

/**
 * The answer of GET /api/plant/cells (or one `cells` event's data), with every field typed.
 * @param {any} data @returns {PlantData}
 */
export function readPlant(data) {
  const b = data?.broker && typeof data.broker === 'object' ? data.broker : {};
  return {
    broker: { state: str(b.state) || 'off', since: num(b.since), error: str(b.error) },
    cells: arr(data?.cells).map(readCell),
  };
}

// ---- status and order ----

const CALM_SAFETY = ['normal', ''];

/**
 * The cell's own UI as a link target: only http(s) URLs (a broker message is not trusted to name a script);
 * '' for none.
 * @param {string} url
 */
export function cellLink(url) {
  return /^https?:\/\/[^\s]+$/i.test(url.trim()) ? url.trim() : '';
}

/** What a card is called: its birth name, or its node id until it sent one. @param {PlantCell} c */
export const cellName = (c) => c.name || c.node || c.id;

/** An active alarm: an alarm count, an error-level alarm, or a safety state other than normal. @param {PlantCell} c */
export function hasAlarm(c) {
  return c.alarms > 0 || c.severity >= 2 || !CALM_SAFETY.includes(c.safety.trim().toLowerCase());
}

/** "Protective stop" from "protective stop". @param {string} s */
const sentence = (s) => (s ? s[0].toUpperCase() + s.slice(1) : s);

/**
 * A safety state (SafetyStatus.status: normal, warning, fault, safeguard stop, protective stop, emergency stop) in
 * words, as a sentence; an unknown one as it came.
 * @param {string} s
 */
function safetyWords(s) {
  switch (s.trim().toLowerCase()) {
    case 'warning': return m.plant_safety_warning();
    case 'fault': return m.plant_safety_fault();
    case 'safeguard stop': return m.plant_safety_safeguard_stop();
    case 'protective stop': return m.plant_safety_protective_stop();
    case 'emergency stop': return m.plant_safety_emergency_stop();
    default: return sentence(s.trim());
  }
}

/**
 * The cell's status: alarm (wins, even for an offline cell whose last report had one), offline, ok; with its label.
 * @param {PlantCell} c @returns {{ status: CellStatusKind, text: string }}
 */
export function cellStatus(c) {
  if (hasAlarm(c)) {
    const parts = [];
    if (c.alarms > 0) parts.push(m.plant_n_active_alarms({ count: c.alarms }));
    if (!CALM_SAFETY.includes(c.safety.trim().toLowerCase())) parts.push(safetyWords(c.safety));
    if (!parts.length) parts.push(m.plant_error_alarm());
    if (!c.online) parts.push(m.plant_offline_part());
    return { status: 'alarm', text: sentence(parts.join(' · ')) };
  }
  if (!c.online) return { status: 'offline', text: m.plant_offline() };
  // Its BFF is up but cannot reach its ROS side: nothing it reports about the cell is current.
  if (!c.ros) return { status: 'offline', text: m.plant_no_ros_data() };
  return { status: 'ok', text: m.plant_ok() };
}

const RANK = { alarm: 0, offline: 1, ok: 2 };
const byName = new Intl.Collator(undefined, { numeric: true, sensitivity: 'base' });

/**
 * Alarms first, then offline cells, then the rest; by name (node without one) within each, then by id.
 * Returns a new array.
 * @param {PlantCell[]} cells
 */
export function sortCells(cells) {
  return [...cells].sort((a, b) =>
    RANK[cellStatus(a).status] - RANK[cellStatus(b).status]
    || byName.compare(cellName(a), cellName(b))
    || (a.id < b.id ? -1 : a.id > b.id ? 1 : 0));
}

// ---- times ----

/**
 * A local wall-clock time (24 h, in the user's locale): "10:32" on the same day as `nowMs`, "24 Nov 10:32" otherwise.
 * @param {number} ms @param {number} nowMs
 */
export function formatClock(ms, nowMs) {
  const d = new Date(ms);
  const n = new Date(nowMs);
  const hm = fmtDateTime(d, { hour: '2-digit', minute: '2-digit', hourCycle: 'h23' });
  const sameDay = d.getFullYear() === n.getFullYear() && d.getMonth() === n.getMonth() && d.getDate() === n.getDate();
  if (sameDay) return hm;
  // The month as a date writes it in the user's language ("Nov", "nov", "Nov.", Finnish "11").
  const parts = new Intl.DateTimeFormat(getLocale(), { day: 'numeric', month: 'short' }).formatToParts(d);
  const month = parts.find((p) => p.type === 'month')?.value ?? String(d.getMonth() + 1);
  return m.plant_clock_date({ day: fmtNumber(d.getDate()), month, time: hm });
}

/** A duration, coarse: "40 s", "5 min", "2 h 5 min", "3 d". @param {number} ms */
export function formatDuration(ms) {
  const s = Math.max(0, Math.floor(ms / 1000));
  if (s < 60) return m.plant_dur_s({ n: fmtNumber(s) });
  const min = Math.floor(s / 60);
  if (min < 60) return m.plant_dur_min({ n: fmtNumber(min) });
  const h = Math.floor(min / 60);
  if (h < 48) return min % 60 ? m.plant_dur_h_min({ h: fmtNumber(h), min: fmtNumber(min % 60) }) : m.plant_dur_h({ h: fmtNumber(h) });
  return m.plant_dur_d({ n: fmtNumber(Math.floor(h / 24)) });
}

/**
 * "since 10:32 (5 min)"; '' when the time is unknown (0 or not a number).
 * @param {number} sinceMs @param {number} nowMs
 */
export function formatSince(sinceMs, nowMs) {
  if (typeof sinceMs !== 'number' || !Number.isFinite(sinceMs) || sinceMs <= 0) return '';
  return m.plant_since({ time: formatClock(sinceMs, nowMs), duration: formatDuration(nowMs - sinceMs) });
}

/** "Online since 10:32 (5 min)", "Offline since 10:40 (3 min)", or just "Online"/"Offline". @param {PlantCell} c @param {number} nowMs */
export function onlineText(c, nowMs) {
  const since = formatSince(c.since, nowMs);
  const status = c.online ? m.plant_online() : m.plant_offline();
  return since ? m.plant_status_since({ status, since }) : status;
}

/** A cycle time: "8.3 s", "2 min 5 s"; "—" for none (0) or unknown. @param {number} s */
export function formatCycleTime(s) {
  if (typeof s !== 'number' || !Number.isFinite(s) || s <= 0) return '—';
  if (s < 59.95) return m.plant_cycle_s({ s: fmtFixed(s, 1) });
  const whole = Math.round(s);
  return m.plant_cycle_min_s({ min: fmtNumber(Math.floor(whole / 60)), s: fmtNumber(whole % 60) });
}

// ---- the card's lines ----

/**
 * "12 cycles in the last hour · running 85 % of 2 h 10 min"; '' without statistics.
 * @param {PlantCell} c
 */
export function shiftText(c) {
  const s = c.shift;
  if (!s) return '';
  const cycles = m.plant_shift_cycles({ count: s.cycles_last_hour });
  if (s.running_share === null || s.observed_s <= 0) return cycles;
  return m.plant_shift_running({ cycles, share: fmtNumber(Math.round(s.running_share * 100)), duration: formatDuration(s.observed_s * 1000) });
}

/**
 * The alarm line: active (styled as an alarm) when there is an alarm count or an error-level alarm.
 * @param {PlantCell} c @returns {{ active: boolean, text: string }}
 */
export function alarmLine(c) {
  const active = c.alarms > 0 || c.severity >= 2;
  if (!active) return { active, text: m.plant_no_active_alarm() };
  const count = c.alarms > 0 ? m.plant_n_active_alarms({ count: c.alarms }) : m.plant_error_alarm();
  return { active, text: c.alarm ? m.plant_alarm_with_text({ count, text: c.alarm }) : count };
}

/** The safety state when it is not normal ('' otherwise). @param {PlantCell} c */
export function safetyText(c) {
  const s = c.safety.trim();
  return CALM_SAFETY.includes(s.toLowerCase()) ? '' : safetyWords(s);
}

/** A process state (ProcessState.state) in words; an unknown one as it came. @param {string} s */
function processWords(s) {
  switch (s) {
    case 'idle': return m.plant_process_idle();
    case 'running': return m.plant_process_running();
    case 'pausing': return m.plant_process_pausing();
    case 'paused': return m.plant_process_paused();
    case 'stopping': return m.plant_process_stopping();
    case 'error': return m.plant_process_error();
    case 'unknown': return m.plant_process_unknown();
    default: return s;
  }
}

/** "running · Pick part", "idle", "—". @param {PlantCell} c */
export function processText(c) {
  return [processWords(c.process), c.operation].filter(Boolean).join(' · ') || '—';
}

/** A robot mode (the UR driver's robot mode name) in words; an unknown one as it came. @param {string} mode */
function robotModeWords(mode) {
  switch (mode) {
    case 'NO_CONTROLLER': return m.plant_robot_mode_no_controller();
    case 'DISCONNECTED': return m.plant_robot_mode_disconnected();
    case 'CONFIRM_SAFETY': return m.plant_robot_mode_confirm_safety();
    case 'BOOTING': return m.plant_robot_mode_booting();
    case 'POWER_OFF': return m.plant_robot_mode_power_off();
    case 'POWER_ON': return m.plant_robot_mode_power_on();
    case 'IDLE': return m.plant_robot_mode_idle();
    case 'BACKDRIVE': return m.plant_robot_mode_backdrive();
    case 'RUNNING': return m.plant_robot_mode_running();
    case 'UPDATING_FIRMWARE': return m.plant_robot_mode_updating_firmware();
    default: return mode;
  }
}

/** "ur5: connected, RUNNING", "ur5: not connected". @param {PlantRobot} r */
export function robotText(r) {
  const name = r.group || m.plant_robot_default();
  if (!r.connected) return m.plant_robot_not_connected({ name });
  return r.mode ? m.plant_robot_connected_mode({ name, mode: robotModeWords(r.mode) }) : m.plant_robot_connected({ name });
}

/** "3 of 4 modules active"; '' with no modules. @param {PlantModule[]} modules */
export function modulesText(modules) {
  if (!modules.length) return '';
  const active = modules.filter((x) => x.state.toLowerCase() === 'active').length;
  return m.plant_modules_active({ active: fmtNumber(active), count: modules.length });
}

/** A module's state (ModuleStates) in words; an unknown one as it came. @param {string} state */
export function moduleStateText(state) {
  switch (state.toLowerCase()) {
    case 'active': return m.plant_module_active();
    case 'inactive': return m.plant_module_inactive();
    case 'transitioning': return m.plant_module_transitioning();
    case 'incomplete': return m.plant_module_incomplete();
    default: return state;
  }
}

// ---- the header ----

/**
 * The plant link's state as a badge tone and a label.
 * @param {PlantBroker} b @returns {{ tone: 'ok' | 'info' | 'danger' | 'neutral', text: string }}
 */
export function brokerView(b) {
  switch (b.state) {
    case 'connected': return { tone: 'ok', text: m.plant_broker_connected() };
    case 'connecting': return { tone: 'info', text: m.plant_broker_connecting() };
    case 'down': return { tone: 'danger', text: b.error ? m.plant_broker_unreachable_error({ error: b.error }) : m.plant_broker_unreachable() };
    case 'off': return { tone: 'neutral', text: m.plant_broker_off() };
    default: return { tone: 'neutral', text: b.state ? m.plant_broker_state({ state: b.state }) : m.plant_broker_unknown() };
  }
}

/** "2 cells, 1 with alarms", "3 cells, none with alarms, 1 offline". @param {PlantCell[]} cells */
export function countText(cells) {
  let alarms = 0;
  let offline = 0;
  for (const c of cells) {
    const s = cellStatus(c).status;
    if (s === 'alarm') alarms++;
    else if (s === 'offline') offline++;
  }
  const parts = [m.plant_n_cells({ count: cells.length }), alarms ? m.plant_n_with_alarms({ count: fmtNumber(alarms) }) : m.plant_none_with_alarms()];
  if (offline) parts.push(m.plant_n_offline({ count: fmtNumber(offline) }));
  return parts.join(', ');
}
