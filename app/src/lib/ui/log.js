/**
 * A feature's log (cell_msgs/LogEntries: the node's bounded history, newest last, latched) as the log panel shows
 * it: newest first, at most `max` lines, each level with a label (colour is never the only signal).
 */

import { m } from '$lib/paraglide/messages.js';
import { fmtDateTime } from '../core/i18n.js';
import { paramsOf, saidText } from '../core/said.js';

/** @typedef {'info' | 'warning' | 'error'} LogLevel */
/** @typedef {{ key: string, at: number | null, level: LogLevel, label: string, text: string }} LogLine */

/** A level's label in the user's language. @param {LogLevel} level */
export function levelLabel(level) {
  switch (level) {
    case 'error': return m.shell_log_error();
    case 'warning': return m.shell_log_warning();
    default: return m.shell_log_info();
  }
}

/** @param {any} t  a ROS time ({secs, nsecs} or {sec, nanosec}) @returns {number | null} ms since the epoch */
export function rosTimeMs(t) {
  const s = Number(t?.secs ?? t?.sec);
  const ns = Number(t?.nsecs ?? t?.nanosec ?? 0);
  return Number.isFinite(s) && s > 0 ? s * 1000 + Math.round(ns / 1e6) : null;
}

/** @param {any} l @returns {LogLevel} */
export function levelOf(l) {
  const s = String(l ?? '').toLowerCase();
  if (s === 'error' || s === 'fatal') return 'error';
  if (s === 'warning' || s === 'warn') return 'warning';
  return 'info';
}

/**
 * @param {any} msg  cell_msgs/LogEntries, or null
 * @param {number} [max]
 * @param {import('../core/said.js').Rename} [rename]  how the page names a parameter's value (an operation's title)
 * @returns {LogLine[]}
 */
export function logLines(msg, max = 200, rename) {
  const entries = Array.isArray(msg?.entries) ? msg.entries : [];
  const out = [];
  for (let i = entries.length - 1; i >= 0 && out.length < max; i--) {
    const e = entries[i];
    const level = levelOf(e?.level);
    const at = rosTimeMs(e?.stamp);
    const text = String(e?.text ?? '');
    const said = typeof e?.code === 'string' && e.code ? saidText(e.code, paramsOf(e.params), text, rename) : text;
    out.push({ key: `${i}:${at ?? ''}`, at, level, label: levelLabel(level), text: said });
  }
  return out;
}

/** @param {number | null} at @returns {string} HH:MM:SS local time (24 h, in the user's locale: 10.32.05 in Finnish) */
export function clockTime(at) {
  if (at === null) return '--:--:--';
  return fmtDateTime(at, { hour: '2-digit', minute: '2-digit', second: '2-digit', hourCycle: 'h23' });
}
