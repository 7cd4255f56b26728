/**
 * The alarms feature's plain logic: ROS names, severities, the order of the list, the overall status's look, and
 * which alarm the banner shows. No Svelte, no ROS: tests import it directly.
 */

import { m } from '$lib/paraglide/messages.js';
import { getLocale, cellText } from '../../core/i18n.js';
import { paramsOf, saidText } from '../../core/said.js';

export const FEATURE_ID = 'alarms';

export const NAMES = Object.freeze({
  list: { topic: '/cell/alarms/list', type: 'cell_msgs/AlarmList' },
  status: { topic: '/cell/alarms/status', type: 'cell_msgs/SafetyStatus' },
  reset: { service: '/cell/alarms/reset', type: 'std_srvs/Trigger' },
});

/** Both topics are latched and republished about once a second: older than this, they are stale. */
export const STATUS_PERIOD_MS = 3000;

/** Severity as colour and label (cell_msgs/Alarm: 0 info, 1 warning, 2 error); the label in the user's language. */
export const SEVERITY = Object.freeze([
  Object.freeze({ tone: 'info', get label() { return m.alarms_severity_info(); } }),
  Object.freeze({ tone: 'warn', get label() { return m.alarms_severity_warning(); } }),
  Object.freeze({ tone: 'danger', get label() { return m.alarms_severity_error(); } }),
]);

/** @param {number} s @returns {{ tone: string, label: string }} */
export const severityView = (s) => {
  const v = SEVERITY[Math.max(0, Math.min(SEVERITY.length - 1, Math.trunc(Number(s) || 0)))];
  return { tone: v.tone, label: v.label };
};

/**
 * @typedef {object} AlarmView
 * @property {string} key  id + the how-many-th activation: a new key is a new alarm for the banner
 * @property {string} id
 * @property {string | Record<string, string>} text  the robot PC's text: shown through alarmText
 * @property {string} code  what the text says, for the catalogue ('' : none; cell_msgs/Alarm)
 * @property {Record<string, string>} params  the code's parameters
 * @property {number} severity
 * @property {boolean} active
 * @property {number | null} since  ms since the epoch (first seen)
 * @property {number | null} lastSeen
 * @property {string} source
 * @property {number} count
 */

/** A ROS time ({secs, nsecs}, or {sec, nanosec}) in ms since the epoch; null when unset (0). @param {any} t */
export function rosTimeMs(t) {
  if (!t || typeof t !== 'object') return null;
  const s = Number(t.secs ?? t.sec ?? 0);
  const n = Number(t.nsecs ?? t.nanosec ?? 0);
  const ms = s * 1000 + n / 1e6;
  return Number.isFinite(ms) && ms > 0 ? ms : null;
}

/**
 * cell_msgs/AlarmList as the page shows it: active first, then by severity (highest first), then newest first.
 * @param {any} msg @returns {AlarmView[]}
 */
export function alarmViews(msg) {
  const list = Array.isArray(msg?.alarms) ? msg.alarms : [];
  return list
    .filter((/** @type {any} */ a) => a && typeof a.id === 'string')
    .map((/** @type {any} */ a) => {
      const count = Number(a.count) || 1;
      const since = rosTimeMs(a.since);
      return {
        key: `${a.id}#${count}@${since ?? 0}`,
        id: a.id,
        text: (typeof a.text === 'string' && a.text) || (a.text && typeof a.text === 'object') ? a.text : a.id,
        code: typeof a.code === 'string' ? a.code : '',
        params: paramsOf(a.params),
        severity: Number(a.severity) || 0,
        active: !!a.active,
        since,
        lastSeen: rosTimeMs(a.last_seen),
        source: typeof a.source === 'string' ? a.source : '',
        count,
      };
    })
    .sort((/** @type {AlarmView} */ a, /** @type {AlarmView} */ b) =>
      Number(b.active) - Number(a.active) || b.severity - a.severity || (b.since ?? 0) - (a.since ?? 0));
}

/**
 * An alarm's words in the user's language: the cell file's text for its id (alarms.texts), else the app's
 * catalogue text of its code with its parameters (a plain number in the user's format), else the robot PC's own
 * text (English, or a device's words).
 * @param {{ id?: string, text: string | Record<string, string>, code?: string, params?: Record<string, string> }} a
 * @param {Record<string, string | Record<string, string>>} [texts] the cell file's alarms.texts
 * @returns {string}
 */
export function alarmText(a, texts) {
  const own = a.id && texts && Object.hasOwn(texts, a.id) ? texts[a.id] : undefined;
  if (own) return cellText(own);
  return a.code ? saidText(`alarm.${a.code}`, a.params ?? {}, cellText(a.text)) : cellText(a.text);
}

/**
 * The safety status's text (cell_msgs/SafetyStatus: its most severe active alarm's, or "no active alarm") in the
 * user's language, as alarmText says that alarm.
 * @param {any} status @param {Record<string, string | Record<string, string>>} [texts]
 * @returns {string}
 */
export function statusText(status, texts) {
  const text = typeof status?.text === 'string' ? status.text : '';
  if (!text) return '';
  if (text === NO_ACTIVE_ALARM) return m.alarms_no_active_alarm();
  return alarmText({ id: typeof status.alarm_id === 'string' ? status.alarm_id : '', text, code: typeof status.code === 'string' ? status.code : '', params: paramsOf(status.params) }, texts);
}

/**
 * The overall status's name in the user's language (cell_msgs/SafetyStatus: normal, warning, fault, safeguard stop,
 * protective stop, emergency stop); another one as the robot PC sent it, capitalised.
 * @param {string} s
 */
function statusLabel(s) {
  switch (s) {
    case 'normal': return m.alarms_status_normal();
    case 'warning': return m.alarms_status_warning();
    case 'fault': return m.alarms_status_fault();
    case 'safeguard stop': return m.alarms_status_safeguard_stop();
    case 'protective stop': return m.alarms_status_protective_stop();
    case 'emergency stop': return m.alarms_status_emergency_stop();
    default: return s.charAt(0).toUpperCase() + s.slice(1);
  }
}

/** The overall safety status's look: colour and label. @param {any} status cell_msgs/SafetyStatus */
export function statusView(status) {
  const s = typeof status?.status === 'string' && status.status ? status.status : '';
  if (!s) return { tone: 'neutral', label: m.alarms_status_unknown() };
  const tone = s === 'normal' ? 'ok' : s === 'warning' ? 'warn' : 'danger';
  return { tone, label: statusLabel(s) };
}

/** The robot PC's words for "nothing active" (SafetyStatus.text); any other text is an alarm's, from the cell file. */
export const NO_ACTIVE_ALARM = 'no active alarm';

/**
 * The alarm the banner shows: the newest active one not yet dismissed (dismissing hides the ones shown then; an
 * alarm that comes in later, or comes back, has a new key and shows the banner again).
 * @param {AlarmView[]} alarms @param {Set<string>} dismissed
 * @returns {AlarmView | null}
 */
export function bannerAlarm(alarms, dismissed) {
  const fresh = alarms.filter((a) => a.active && !dismissed.has(a.key));
  fresh.sort((a, b) => (b.since ?? 0) - (a.since ?? 0) || b.severity - a.severity);
  return fresh[0] ?? null;
}

/** How many alarms are active (the menu badge). @param {AlarmView[]} alarms */
export const activeCount = (alarms) => alarms.filter((a) => a.active).length;

/** The locale dates are written in: the user's; English as in Britain (day before month, 24-hour clock). */
const dateLocale = () => (getLocale() === 'en' ? 'en-GB' : getLocale());

/** "14:03:21" today, else "21 Nov 14:03" (in English; the user's locale's format). @param {number | null} ms @param {number} [now] */
export function formatTime(ms, now = Date.now()) {
  if (ms === null) return '—';
  const d = new Date(ms);
  const loc = dateLocale();
  if (new Date(now).toDateString() === d.toDateString()) return d.toLocaleTimeString(loc, { hour: '2-digit', minute: '2-digit', second: '2-digit' });
  return `${d.toLocaleDateString(loc, { day: 'numeric', month: 'short' })} ${d.toLocaleTimeString(loc, { hour: '2-digit', minute: '2-digit' })}`;
}
