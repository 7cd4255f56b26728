/**
 * The inspect feature's plain logic (no Svelte): the ROS names, the log levels, and everything the ROS log card
 * computes: one entry shape from both sources, the merge of the history with the live log, the filters, the texts,
 * the export. Tests import it directly.
 *
 * ROS: /cell/inspect/log (cell_msgs/LogQuery: the robot PC's recent /rosout_agg, filtered, oldest first) and
 * /rosout_agg (rosgraph_msgs/Log) live. The cell file's section (/api/config features.inspect):
 * { log_keep_entries, log_keep_s }, what the inspect node keeps.
 */

export const FEATURE_ID = 'inspect';

export const NAMES = Object.freeze({
  log: { service: '/cell/inspect/log', type: 'cell_msgs/LogQuery' },
  rosout: { topic: '/rosout_agg', type: 'rosgraph_msgs/Log' },
});

/** Entries the page keeps (the oldest go first). */
export const KEEP_ENTRIES = 2000;
/** Rows drawn at most (the newest matching ones). */
export const SHOW_MAX = 300;
/** Live entries are applied at most this often (a 1 kHz log storm stays a few updates a second). */
export const FLUSH_MS = 200;
/**
 * The /rosout_agg subscription's queue_length: what rosbridge and the relay hold for a slow link before they drop
 * the oldest (the relay honours at most 100). No throttle_rate: every entry counts, none is merged away.
 */
export const LIVE_QUEUE_LENGTH = 100;
/** The history asked for on open and after each reconnect: everything, the newest KEEP_ENTRIES. */
export const HISTORY_REQUEST = Object.freeze({ min_level: 0, node: '', text: '', max_entries: KEEP_ENTRIES });

/** The cell file's defaults (config/features/inspect.schema.json) when /api/config does not say. */
export const DEFAULT_KEEP_ENTRIES = 5000;
export const DEFAULT_KEEP_S = 600;

// ---- levels ----

/** @typedef {'debug' | 'info' | 'warn' | 'error' | 'fatal'} LevelName */
/** @typedef {'neutral' | 'info' | 'warn' | 'danger' | 'fatal'} LevelTone */
/** @typedef {{ name: LevelName, value: number, label: string, upper: string, tone: LevelTone }} Level */

/** rosgraph_msgs/Log's levels (RosLogEntry's too), lowest first. Colour (tone) and text (upper) always together. */
export const LEVELS = /** @type {readonly Level[]} */ (Object.freeze([
  { name: 'debug', value: 1, label: 'Debug', upper: 'DEBUG', tone: 'neutral' },
  { name: 'info', value: 2, label: 'Info', upper: 'INFO', tone: 'info' },
  { name: 'warn', value: 4, label: 'Warn', upper: 'WARN', tone: 'warn' },
  { name: 'error', value: 8, label: 'Error', upper: 'ERROR', tone: 'danger' },
  { name: 'fatal', value: 16, label: 'Fatal', upper: 'FATAL', tone: 'fatal' },
]));

const BY_NAME = new Map(LEVELS.map((l) => [l.name, l]));

/**
 * A level's name from its number (1 debug, 2 info, 4 warn, 8 error, 16 fatal); a number between two levels counts
 * as the lower one, anything below 2 (or not a number) as debug. Names ("WARN", "warning") are accepted too.
 * @param {any} n @returns {LevelName}
 */
export function levelName(n) {
  if (typeof n === 'string' && !/^\s*\d+\s*$/.test(n)) {
    const s = n.trim().toLowerCase();
    if (s === 'warning') return 'warn';
    return BY_NAME.has(/** @type {LevelName} */ (s)) ? /** @type {LevelName} */ (s) : 'info';
  }
  const v = Number(n);
  if (!Number.isFinite(v)) return 'debug';
  if (v >= 16) return 'fatal';
  if (v >= 8) return 'error';
  if (v >= 4) return 'warn';
  if (v >= 2) return 'info';
  return 'debug';
}

/** A level by name (or number): value, label, upper-case name, tone. @param {any} l @returns {Level} */
export function levelView(l) {
  const name = typeof l === 'string' && BY_NAME.has(/** @type {LevelName} */ (l)) ? /** @type {LevelName} */ (l) : levelName(l);
  return /** @type {Level} */ (BY_NAME.get(name));
}

// ---- entries ----

/**
 * One entry of the ROS log, from either source.
 * @typedef {object} LogEntry
 * @property {number} t_ms  when the node logged it, ms since the epoch (sub-ms kept)
 * @property {number} level  1, 2, 4, 8 or 16
 * @property {LevelName} levelName
 * @property {string} node  e.g. "/process_node"
 * @property {string} msg
 * @property {string} file
 * @property {string} function
 * @property {number} line
 * @property {string} key  the same for the same entry from either source (stamp to the µs, node, line, message)
 */

/** Characters of the message the key holds: enough to tell entries apart, and the robot PC cuts very long ones. */
export const KEY_MSG_CHARS = 200;

/** @param {any} v */
const str = (v) => (typeof v === 'string' ? v : v === null || v === undefined ? '' : String(v));

/**
 * A ROS time ({secs, nsecs} or {sec, nanosec}) in µs since the epoch, rounded; null when unset (0) or invalid.
 * @param {any} t @returns {number | null}
 */
export function rosTimeUs(t) {
  if (!t || typeof t !== 'object') return null;
  const us = Number(t.secs ?? t.sec ?? 0) * 1e6 + Number(t.nsecs ?? t.nanosec ?? 0) / 1e3;
  return Number.isFinite(us) && us > 0 ? Math.round(us) : null;
}

/**
 * One entry in the page's shape, from the service's RosLogEntry ({stamp, level, node, msg, file, function, line})
 * or the topic's rosgraph_msgs/Log ({header: {stamp}, level, name, msg, file, function, line, topics}).
 * An entry without a stamp gets `fallbackMs` (when it arrived).
 * @param {any} m @param {number} [fallbackMs] @returns {LogEntry}
 */
export function normaliseEntry(m, fallbackMs = Date.now()) {
  const us = rosTimeUs(m?.stamp ?? m?.header?.stamp) ?? Math.round(fallbackMs * 1000);
  const name = levelName(m?.level);
  const node = str(m?.node ?? m?.name);
  const msg = str(m?.msg);
  const line = Math.max(0, Math.trunc(Number(m?.line) || 0));
  return {
    t_ms: us / 1000,
    level: levelView(name).value,
    levelName: name,
    node,
    msg,
    file: str(m?.file),
    function: str(m?.function),
    line,
    key: `${us}|${node}|${line}|${msg.slice(0, KEY_MSG_CHARS)}`,
  };
}

/** @param {string} key @returns {[number, string]} the stamp in µs and the rest (node, line, message) */
function splitKey(key) {
  const i = key.indexOf('|');
  return [Number(key.slice(0, i)), key.slice(i + 1)];
}

/**
 * The kept entries plus new ones (history or live, in any order): oldest first, each entry once, at most `max`
 * (the oldest go). The same entry is the same stamp, node, line and message; the stamp is compared to within 1 µs
 * because the robot PC's history stores it as float seconds, which moves the nanoseconds a little.
 * `kept` must already be merged (no duplicates); it is returned as is when nothing is new.
 * @param {LogEntry[]} kept @param {LogEntry[]} incoming @param {number} [max]
 * @returns {{ entries: LogEntry[], added: number }}  added: new entries (before the cap)
 */
export function mergeEntries(kept, incoming, max = KEEP_ENTRIES) {
  if (!incoming.length) return { entries: kept, added: 0 };
  /** @type {Map<string, Set<number>>} */
  const seen = new Map();
  /** @param {number} us @param {string} rest */
  const note = (us, rest) => {
    let s = seen.get(rest);
    if (!s) seen.set(rest, (s = new Set()));
    s.add(us);
  };
  for (const e of kept) note(...splitKey(e.key));
  /** @type {LogEntry[]} */
  const fresh = [];
  for (const e of incoming) {
    const [us, rest] = splitKey(e.key);
    const s = seen.get(rest);
    if (s && (s.has(us) || s.has(us - 1) || s.has(us + 1))) continue;
    note(us, rest);
    fresh.push(e);
  }
  if (!fresh.length) return { entries: kept, added: 0 };
  const last = kept.length ? kept[kept.length - 1].t_ms : -Infinity;
  const inOrder = fresh.every((e, i) => e.t_ms >= (i ? fresh[i - 1].t_ms : last));
  // Stable sort: entries with the same stamp keep their order of arrival.
  const all = inOrder ? kept.concat(fresh) : kept.concat(fresh).sort((a, b) => a.t_ms - b.t_ms);
  return { entries: all.length > max ? all.slice(all.length - max) : all, added: fresh.length };
}

// ---- filters ----

/** @typedef {{ minLevel: LevelName, node: string, text: string }} LogFilters */

/** @type {Readonly<LogFilters>} */
export const NO_FILTERS = Object.freeze({ minLevel: 'debug', node: '', text: '' });

/** Whether any filter narrows the list. @param {LogFilters} f */
export const isFiltered = (f) => levelView(f.minLevel).value > 1 || !!f.node || !!f.text.trim();

/**
 * The entries at `minLevel` and above, of `node` ('' any), whose message, node or file contains `text` (any case,
 * '' any): the robot PC's query, client-side. Order kept.
 * @param {LogEntry[]} entries @param {LogFilters} f @returns {LogEntry[]}
 */
export function filterEntries(entries, f) {
  const min = levelView(f.minLevel).value;
  const node = f.node;
  const needle = f.text.trim().toLowerCase();
  if (min <= 1 && !node && !needle) return entries;
  return entries.filter((e) =>
    e.level >= min
    && (!node || e.node === node)
    && (!needle || e.msg.toLowerCase().includes(needle) || e.node.toLowerCase().includes(needle) || e.file.toLowerCase().includes(needle)));
}

/** The newest `max` entries, newest first (entries are oldest first). @param {LogEntry[]} entries @param {number} [max] */
export function newestFirst(entries, max = SHOW_MAX) {
  const out = [];
  for (let i = entries.length - 1; i >= 0 && out.length < max; i--) out.push(entries[i]);
  return out;
}

/**
 * The nodes seen, sorted, each once (empty names left out); `keep` (the node picked) stays listed even when its
 * entries are gone.
 * @param {LogEntry[]} entries @param {string} [keep] @returns {string[]}
 */
export function nodeList(entries, keep = '') {
  const s = new Set();
  for (const e of entries) if (e.node) s.add(e.node);
  if (keep) s.add(keep);
  return [...s].sort((a, b) => (a < b ? -1 : a > b ? 1 : 0));
}

// ---- texts ----

/** @param {number} n */
const two = (n) => String(n).padStart(2, '0');

/** "14:05:12.123", local time. @param {number} tMs */
export function formatClock(tMs) {
  if (typeof tMs !== 'number' || !Number.isFinite(tMs)) return '--:--:--.---';
  const d = new Date(Math.floor(tMs));
  return `${two(d.getHours())}:${two(d.getMinutes())}:${two(d.getSeconds())}.${String(d.getMilliseconds()).padStart(3, '0')}`;
}

/** The ISO time of an entry (UTC, ms): "2026-11-26T14:05:12.123Z". @param {number} tMs */
export const isoTime = (tMs) => new Date(Math.floor(tMs)).toISOString();

/** Where it was logged: "process.py:120", '' when the node did not say. @param {LogEntry} e */
export const sourceText = (e) => (e.file ? (e.line > 0 ? `${e.file}:${e.line}` : e.file) : '');

/** @param {number} n @param {string} one @param {string} [many] */
const count = (n, one, many = `${one}s`) => `${n} ${n === 1 ? one : many}`;

/** "45 s", "10 min", "2 h 5 min". @param {number} s */
export function spanText(s) {
  const v = Math.max(0, Number(s) || 0);
  if (v < 60) return `${Math.round(v)} s`;
  const min = Math.round(v / 60);
  if (min < 120) return `${min} min`;
  const h = Math.floor(min / 60), m = min % 60;
  return m ? `${h} h ${m} min` : `${h} h`;
}

/**
 * What the robot PC keeps, from the cell file's section: "The robot PC keeps the last 10 min of the ROS log, at
 * most 5000 entries; this page keeps the newest 2000."
 * @param {any} section
 */
export function keepText(section) {
  const n = Number(section?.log_keep_entries);
  const s = Number(section?.log_keep_s);
  const entries = Number.isFinite(n) && n > 0 ? n : DEFAULT_KEEP_ENTRIES;
  const secs = Number.isFinite(s) && s > 0 ? s : DEFAULT_KEEP_S;
  return `The robot PC keeps the last ${spanText(secs)} of the ROS log, at most ${count(entries, 'entry', 'entries')}; this page keeps the newest ${KEEP_ENTRIES}.`;
}

/**
 * @typedef {object} HistoryAnswer  /cell/inspect/log's response
 * @property {any[]} entries
 * @property {number} matched
 * @property {number} dropped
 * @property {number} kept_s
 */

/**
 * The history's status line from the service's answer (asked without filters, so `matched` is all it keeps):
 * "History: the last 10 min (5000 entries kept on the robot PC, 12 dropped) · the newest 2000 loaded".
 * @param {HistoryAnswer | null | undefined} a
 */
export function historyText(a) {
  if (!a) return '';
  const loaded = Array.isArray(a.entries) ? a.entries.length : 0;
  const matched = Math.max(loaded, Number(a.matched) || 0);
  const dropped = Math.max(0, Number(a.dropped) || 0);
  if (matched === 0) return `History: no entries kept on the robot PC yet (${dropped} dropped)`;
  const text = `History: the last ${spanText(a.kept_s)} (${count(matched, 'entry', 'entries')} kept on the robot PC, ${dropped} dropped)`;
  return loaded < matched ? `${text} · the newest ${loaded} loaded` : text;
}

/**
 * Above the list: "Showing the newest 300 of 1234 entries", "12 entries", with " (filtered from 2000)" when the
 * filters hide some. '' when nothing is kept.
 * @param {number} shown @param {number} matching @param {number} total
 */
export function shownText(shown, matching, total) {
  if (total === 0) return '';
  const from = matching < total ? ` (filtered from ${total})` : '';
  if (matching === 0) return `No entries match the filters (${count(total, 'entry', 'entries')} kept)`;
  if (shown < matching) return `Showing the newest ${shown} of ${matching} entries${from}`;
  return `${count(matching, 'entry', 'entries')}${from}`;
}

/** While paused: "12 new entries" (not shown until Resume). @param {number} n */
export const newEntriesText = (n) => `${count(n, 'new entry', 'new entries')}`;

/**
 * Why the log is not live, as a title and a sentence (null when it is live).
 * @param {'offline' | 'disconnected' | null} why @returns {{ title: string, text: string } | null}
 */
export function notLiveView(why) {
  if (why === 'offline') return { title: 'Offline', text: 'the log is not live. New entries appear again once the server answers.' };
  if (why === 'disconnected') {
    return { title: 'ROS disconnected', text: 'the log is not live. New entries appear again once reconnected, with the history missed meanwhile.' };
  }
  return null;
}

// ---- export ----

/**
 * One line of the export: ISO time, level, node, message, file:line (newlines in the message written as \n).
 * "2026-11-26T14:05:12.123Z WARN /process_node Move failed: protective stop process.py:120"
 * @param {LogEntry} e
 */
export function exportLine(e) {
  const msg = e.msg.replace(/\r?\n/g, '\\n');
  const src = e.file ? ` ${e.file}:${e.line}` : '';
  return `${isoTime(e.t_ms)} ${levelView(e.levelName).upper} ${e.node || '-'} ${msg}${src}`;
}

/** The export file's text: one line per entry, oldest first. @param {LogEntry[]} entries */
export const exportText = (entries) => entries.map((e) => `${exportLine(e)}\n`).join('');

/**
 * The export file's name, from the time of the export (UTC, as the recorder names its files):
 * "ros-log-20261126T140512Z.log".
 * @param {number} nowMs
 */
export function exportFileName(nowMs) {
  const iso = new Date(nowMs).toISOString(); // 2026-11-26T14:05:12.123Z
  return `ros-log-${iso.slice(0, 19).replace(/[-:]/g, '')}Z.log`;
}
