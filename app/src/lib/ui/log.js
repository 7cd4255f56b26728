/**
 * A feature's log (cell_msgs/LogEntries: the node's bounded history, newest last, latched) as the log panel shows
 * it: newest first, at most `max` lines, each level with a label (colour is never the only signal).
 */

/** @typedef {'info' | 'warning' | 'error'} LogLevel */
/** @typedef {{ key: string, at: number | null, level: LogLevel, label: string, text: string }} LogLine */

export const LEVEL_LABELS = Object.freeze({ info: 'Info', warning: 'Warning', error: 'Error' });

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
 * @returns {LogLine[]}
 */
export function logLines(msg, max = 200) {
  const entries = Array.isArray(msg?.entries) ? msg.entries : [];
  const out = [];
  for (let i = entries.length - 1; i >= 0 && out.length < max; i--) {
    const e = entries[i];
    const level = levelOf(e?.level);
    const at = rosTimeMs(e?.stamp);
    out.push({ key: `${i}:${at ?? ''}`, at, level, label: LEVEL_LABELS[level], text: String(e?.text ?? '') });
  }
  return out;
}

/** @param {number | null} at @returns {string} HH:MM:SS local time */
export function clockTime(at) {
  if (at === null) return '--:--:--';
  const d = new Date(at);
  return [d.getHours(), d.getMinutes(), d.getSeconds()].map((n) => String(n).padStart(2, '0')).join(':');
}
