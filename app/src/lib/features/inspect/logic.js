/**
 * The inspect feature's plain logic (no Svelte): the ROS names, the views (tabs), the log levels, and everything
 * the ROS log card computes: one entry shape from both sources, the merge of the history with the live log, the
 * filters, the texts, the export. The Topics and Nodes views' logic (the graph, filters, measured figures, the last
 * message as a tree) is in the second half, the Diagnostics view's (levels, the tree, sorting, filters) at the end.
 * Tests import it directly.
 *
 * ROS: /cell/inspect/log (cell_msgs/LogQuery: the robot PC's recent /rosout_agg, filtered, oldest first) and
 * /rosout_agg (rosgraph_msgs/Log) live; /cell/inspect/graph (topics and nodes), /cell/inspect/topic_stats (a topic's
 * rate and bandwidth, measured while asked), /cell/inspect/echo (a topic's last message as JSON) and
 * /cell/inspect/diagnostics (diagnostic_msgs/DiagnosticArray, latched, ~1 Hz: every status heard on /diagnostics, the
 * silent ones marked STALE). The cell file's
 * section (/api/config features.inspect): { log_keep_entries, log_keep_s, can_echo } (can_echo: this role may read
 * any topic's last message).
 */

import { m } from '$lib/paraglide/messages.js';
import { fmtFixed, fmtDateTime } from '../../core/i18n.js';

export const FEATURE_ID = 'inspect';

export const NAMES = Object.freeze({
  log: { service: '/cell/inspect/log', type: 'cell_msgs/LogQuery' },
  rosout: { topic: '/rosout_agg', type: 'rosgraph_msgs/Log' },
  graph: { service: '/cell/inspect/graph', type: 'cell_msgs/GetRosGraph' },
  topicStats: { service: '/cell/inspect/topic_stats', type: 'cell_msgs/TopicStats' },
  echo: { service: '/cell/inspect/echo', type: 'cell_msgs/TopicEcho' },
  diagnostics: { topic: '/cell/inspect/diagnostics', type: 'diagnostic_msgs/DiagnosticArray' },
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
/**
 * @typedef {{ name: LevelName, value: number, label: string, upper: string, badge: string, tone: LevelTone }} Level
 * label: the filter's name, badge: the row's (both in the user's language); upper: ROS's name (the export's).
 */

/** rosgraph_msgs/Log's levels (RosLogEntry's too), lowest first. Colour (tone) and text (badge) always together. */
export const LEVELS = /** @type {readonly Level[]} */ (Object.freeze([
  { name: 'debug', value: 1, get label() { return m.inspect_level_debug(); }, upper: 'DEBUG', get badge() { return m.inspect_level_debug_badge(); }, tone: 'neutral' },
  { name: 'info', value: 2, get label() { return m.inspect_level_info(); }, upper: 'INFO', get badge() { return m.inspect_level_info_badge(); }, tone: 'info' },
  { name: 'warn', value: 4, get label() { return m.inspect_level_warn(); }, upper: 'WARN', get badge() { return m.inspect_level_warn_badge(); }, tone: 'warn' },
  { name: 'error', value: 8, get label() { return m.inspect_level_error(); }, upper: 'ERROR', get badge() { return m.inspect_level_error_badge(); }, tone: 'danger' },
  { name: 'fatal', value: 16, get label() { return m.inspect_level_fatal(); }, upper: 'FATAL', get badge() { return m.inspect_level_fatal_badge(); }, tone: 'fatal' },
].map((l) => Object.freeze(l))));

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
 * @param {any} e @param {number} [fallbackMs] @returns {LogEntry}
 */
export function normaliseEntry(e, fallbackMs = Date.now()) {
  const us = rosTimeUs(e?.stamp ?? e?.header?.stamp) ?? Math.round(fallbackMs * 1000);
  const name = levelName(e?.level);
  const node = str(e?.node ?? e?.name);
  const msg = str(e?.msg);
  const line = Math.max(0, Math.trunc(Number(e?.line) || 0));
  return {
    t_ms: us / 1000,
    level: levelView(name).value,
    levelName: name,
    node,
    msg,
    file: str(e?.file),
    function: str(e?.function),
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

/** The time of day to the ms, 24-hour, in the user's locale. */
const CLOCK = /** @type {Intl.DateTimeFormatOptions} */ ({ hour: '2-digit', minute: '2-digit', second: '2-digit', fractionalSecondDigits: 3, hourCycle: 'h23' });

/** "14:05:12.123" (in English), local time. @param {number} tMs */
export function formatClock(tMs) {
  if (typeof tMs !== 'number' || !Number.isFinite(tMs)) return '--:--:--.---';
  return fmtDateTime(Math.floor(tMs), CLOCK);
}

/** The ISO time of an entry (UTC, ms): "2026-11-26T14:05:12.123Z". @param {number} tMs */
export const isoTime = (tMs) => new Date(Math.floor(tMs)).toISOString();

/** Where it was logged: "process.py:120", '' when the node did not say. @param {LogEntry} e */
export const sourceText = (e) => (e.file ? (e.line > 0 ? `${e.file}:${e.line}` : e.file) : '');

/** A whole number in the user's locale, without grouping ("5000", as the counts always read). @param {number} n */
const int = (n) => fmtFixed(n, 0);

/** "45 s", "10 min", "2 h 5 min" (unit symbols; the numbers in the user's locale). @param {number} s */
export function spanText(s) {
  const v = Math.max(0, Number(s) || 0);
  if (v < 60) return `${int(Math.round(v))} s`;
  const min = Math.round(v / 60);
  if (min < 120) return `${int(min)} min`;
  const h = Math.floor(min / 60), mm = min % 60;
  return mm ? `${int(h)} h ${int(mm)} min` : `${int(h)} h`;
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
  return m.inspect_keep({ span: spanText(secs), entries: m.inspect_n_entries({ count: entries }), keep: int(KEEP_ENTRIES) });
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
  if (matched === 0) return m.inspect_history_none({ dropped: int(dropped) });
  const text = m.inspect_history({ span: spanText(a.kept_s), entries: m.inspect_n_entries({ count: matched }), dropped: int(dropped) });
  return loaded < matched ? m.inspect_history_loaded({ history: text, loaded: int(loaded) }) : text;
}

/**
 * Above the list: "Showing the newest 300 of 1234 entries", "12 entries", with " (filtered from 2000)" when the
 * filters hide some. '' when nothing is kept.
 * @param {number} shown @param {number} matching @param {number} total
 */
export function shownText(shown, matching, total) {
  if (total === 0) return '';
  /** @param {string} text */
  const from = (text) => (matching < total ? m.inspect_log_filtered_from({ text, total: int(total) }) : text);
  if (matching === 0) return m.inspect_log_none_match({ entries: m.inspect_n_entries({ count: total }) });
  if (shown < matching) return from(m.inspect_log_showing({ shown: int(shown), matching: int(matching) }));
  return from(m.inspect_n_entries({ count: matching }));
}

/** While paused: "12 new entries" (not shown until Resume). @param {number} n */
export const newEntriesText = (n) => m.inspect_n_new_entries({ count: n });

/**
 * Why the view is not live, as a title and a sentence (null when it is live): the log's, the graph's (Topics and
 * Nodes: what is shown is the last graph read, and measuring stops) or the diagnostics' (the last array received).
 * @param {'offline' | 'disconnected' | null} why @param {'log' | 'graph' | 'diagnostics'} [what]
 * @returns {{ title: string, text: string } | null}
 */
export function notLiveView(why, what = 'log') {
  if (!why) return null;
  const offline = why === 'offline';
  const title = offline ? m.inspect_offline() : m.inspect_ros_disconnected();
  if (what === 'diagnostics') {
    return { title, text: offline ? m.inspect_not_live_diag_offline() : m.inspect_not_live_diag_disconnected() };
  }
  if (what === 'graph') {
    return { title, text: offline ? m.inspect_not_live_graph_offline() : m.inspect_not_live_graph_disconnected() };
  }
  return { title, text: offline ? m.inspect_not_live_log_offline() : m.inspect_not_live_log_disconnected() };
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

// ---- the views (tabs) ----

/** @typedef {'log' | 'topics' | 'nodes' | 'diagnostics'} TabId */

/** The page's views, in the tab list's order (label: in the user's language). */
export const TABS = /** @type {readonly { id: TabId, label: string }[]} */ (Object.freeze([
  { id: 'log', get label() { return m.inspect_log(); } },
  { id: 'topics', get label() { return m.inspect_topics(); } },
  { id: 'nodes', get label() { return m.inspect_nodes(); } },
  { id: 'diagnostics', get label() { return m.inspect_diagnostics(); } },
].map((t) => Object.freeze(t))));

/** A view's id from anything (a URL, storage); the log when unknown. @param {any} v @returns {TabId} */
export const tabId = (v) => TABS.find((t) => t.id === v)?.id ?? 'log';

/**
 * The tab a key moves to in the tab list (the WAI-ARIA tabs pattern: arrows wrap, Home the first, End the last);
 * null for any other key.
 * @param {TabId} current @param {string} key @returns {TabId | null}
 */
export function tabAfterKey(current, key) {
  const i = TABS.findIndex((t) => t.id === current);
  const n = TABS.length;
  if (key === 'ArrowRight') return TABS[(i + 1) % n].id;
  if (key === 'ArrowLeft') return TABS[(i - 1 + n) % n].id;
  if (key === 'Home') return TABS[0].id;
  if (key === 'End') return TABS[n - 1].id;
  return null;
}

// ---- the graph (Topics and Nodes) ----

/** The graph is read again this often while Topics or Nodes is shown. */
export const GRAPH_POLL_MS = 5000;
/** A shown topic's figures are asked for this often (the robot PC measures while asked at least every 10 s). */
export const STATS_POLL_MS = 1000;
/** The last message is asked for this often while shown. */
export const ECHO_POLL_MS = 2000;
/** The master pings every node (up to 1 s each): the graph may take a while on a big cell. */
export const GRAPH_TIMEOUT_MS = 10000;
export const STATS_TIMEOUT_MS = 5000;
export const ECHO_TIMEOUT_MS = 5000;
/** A topic with nothing received after this long reads "no messages" instead of "measuring…". */
export const NO_MESSAGES_AFTER_S = 3;
/** The robot PC's measuring window (cell_msgs/TopicStats window_s reaches it 10 s after measuring starts). */
export const STATS_WINDOW_S = 10;

/**
 * One topic as the master knows it (cell_msgs/TopicInfo).
 * @typedef {object} TopicInfo
 * @property {string} name
 * @property {string} type  '' when the master knows no type for it
 * @property {string[]} publishers  node names
 * @property {string[]} subscribers  node names
 */

/**
 * One node of the graph (cell_msgs/NodeInfo).
 * @typedef {object} NodeInfo
 * @property {string} name
 * @property {boolean} alive  answered a ping just now
 * @property {string} module  the cell file's module that lists it ('' none)
 * @property {string[]} publications
 * @property {string[]} subscriptions
 * @property {string[]} services
 */

/** @param {any} a @returns {string[]} */
const strings = (a) => (Array.isArray(a) ? a.filter((x) => typeof x === 'string') : []);
/** @param {{ name: string }} a @param {{ name: string }} b */
const byName = (a, b) => (a.name < b.name ? -1 : a.name > b.name ? 1 : 0);

/**
 * The graph service's answer in the page's shape: every field present and of its type, entries without a name left
 * out, each list sorted by name (the service sorts too; the page does not depend on it).
 * @param {any} r @returns {{ topics: TopicInfo[], nodes: NodeInfo[] }}
 */
export function normaliseGraph(r) {
  const topics = (Array.isArray(r?.topics) ? r.topics : [])
    .map((/** @type {any} */ t) => ({ name: str(t?.name), type: str(t?.type), publishers: strings(t?.publishers), subscribers: strings(t?.subscribers) }))
    .filter((/** @type {TopicInfo} */ t) => t.name);
  const nodes = (Array.isArray(r?.nodes) ? r.nodes : [])
    .map((/** @type {any} */ n) => ({
      name: str(n?.name), alive: n?.alive === true, module: str(n?.module),
      publications: strings(n?.publications), subscriptions: strings(n?.subscriptions), services: strings(n?.services),
    }))
    .filter((/** @type {NodeInfo} */ n) => n.name);
  return { topics: topics.sort(byName), nodes: nodes.sort(byName) };
}

/** The filter's words, lower case ("joint states" matches "/joint_states" only when both words are in it). @param {string} text */
const words = (text) => String(text ?? '').toLowerCase().split(/\s+/).filter(Boolean);

/**
 * The topics whose name or type contains every word of `text` (any case; '' all). Order kept.
 * @param {TopicInfo[]} topics @param {string} text @returns {TopicInfo[]}
 */
export function filterTopics(topics, text) {
  const w = words(text);
  if (!w.length) return topics;
  return topics.filter((t) => {
    const hay = `${t.name} ${t.type}`.toLowerCase();
    return w.every((x) => hay.includes(x));
  });
}

/**
 * The nodes whose name or module contains every word of `text` (any case; '' all). Order kept.
 * @param {NodeInfo[]} nodes @param {string} text @returns {NodeInfo[]}
 */
export function filterNodes(nodes, text) {
  const w = words(text);
  if (!w.length) return nodes;
  return nodes.filter((n) => {
    const hay = `${n.name} ${n.module}`.toLowerCase();
    return w.every((x) => hay.includes(x));
  });
}

/** "2 pub · 1 sub". @param {TopicInfo} t */
export const pubSubText = (t) => m.inspect_pub_sub({ pub: int(t.publishers.length), sub: int(t.subscribers.length) });

/** @typedef {'topic' | 'node' | 'status'} Counted */

/** "12 topics", "1 node", "3 statuses". @param {number} n @param {Counted} what */
function countOf(n, what) {
  if (what === 'topic') return m.inspect_n_topics({ count: n });
  if (what === 'node') return m.inspect_n_nodes({ count: n });
  return m.inspect_n_statuses({ count: n });
}

/**
 * The count above a list: "12 topics", "3 of 12 topics" when the filter hides some.
 * @param {number} shown @param {number} total @param {Counted} what
 */
export const countText = (shown, total, what) =>
  (shown < total ? m.inspect_n_of({ shown: int(shown), total: countOf(total, what) }) : countOf(total, what));

/**
 * The Nodes view's count: "12 nodes · 1 not responding" (of all nodes, whatever the filter shows).
 * @param {NodeInfo[]} shown @param {NodeInfo[]} all
 */
export function nodeCountText(shown, all) {
  const dead = all.filter((n) => !n.alive).length;
  const base = countText(shown.length, all.length, 'node');
  return dead ? m.inspect_nodes_not_responding({ nodes: base, dead: int(dead) }) : base;
}

/** A node's state as text (never colour alone). @param {NodeInfo} n */
export const aliveText = (n) => (n.alive ? m.inspect_node_alive() : m.inspect_node_not_responding());

// ---- a topic's measured figures ----

/**
 * cell_msgs/TopicStats' response.
 * @typedef {object} TopicStats
 * @property {boolean} ok
 * @property {string} message
 * @property {string} type
 * @property {number} messages  received in the window
 * @property {number} window_s
 * @property {number} rate_hz
 * @property {number} bandwidth_bps  bytes per second
 * @property {number} mean_bytes
 * @property {number} last_age_s  -1: none received yet
 */

/** @param {any} v */
const num = (v) => (typeof v === 'number' && Number.isFinite(v) ? v : Number(v) || 0);

/** The service's answer with every figure a number. @param {any} r @returns {TopicStats} */
export function normaliseStats(r) {
  // A missing age is "none yet", not 0 s (Number(null) is 0).
  const age = typeof r?.last_age_s === 'number' ? r.last_age_s : typeof r?.last_age_s === 'string' && r.last_age_s.trim() ? Number(r.last_age_s) : -1;
  return {
    ok: r?.ok === true, message: str(r?.message), type: str(r?.type),
    messages: Math.max(0, Math.trunc(num(r?.messages))), window_s: Math.max(0, num(r?.window_s)),
    rate_hz: Math.max(0, num(r?.rate_hz)), bandwidth_bps: Math.max(0, num(r?.bandwidth_bps)),
    mean_bytes: Math.max(0, num(r?.mean_bytes)), last_age_s: Number.isFinite(age) && age >= 0 ? age : -1,
  };
}

/**
 * A rate as rostopic hz would read it, about four figures: "124.8 Hz", "9.98 Hz", "0.500 Hz", "1500 Hz".
 * @param {number} hz
 */
export function formatRate(hz) {
  if (typeof hz !== 'number' || !Number.isFinite(hz) || hz < 0) return '—';
  if (hz >= 999.95) return `${int(Math.round(hz))} Hz`;
  if (hz >= 9.995) return `${fmtFixed(hz, 1)} Hz`;
  if (hz >= 0.9995) return `${fmtFixed(hz, 2)} Hz`;
  return `${fmtFixed(hz, 3)} Hz`;
}

const BYTE_UNITS = ['B', 'KB', 'MB', 'GB', 'TB'];

/** A size in bytes, decimal units as rostopic bw: "850 B", "12.3 KB", "123 KB", "1.5 MB". @param {number} n */
export function formatBytes(n) {
  if (typeof n !== 'number' || !Number.isFinite(n) || n < 0) return '—';
  let v = n;
  let i = 0;
  while (v >= 999.5 && i < BYTE_UNITS.length - 1) {
    v /= 1000;
    i++;
  }
  const figure = i === 0 ? int(Math.round(v)) : v < 99.95 ? fmtFixed(v, 1) : int(Math.round(v));
  return `${figure} ${BYTE_UNITS[i]}`;
}

/** "12.3 KB/s". @param {number} bps bytes per second */
export const formatBandwidth = (bps) => (formatBytes(bps) === '—' ? '—' : `${formatBytes(bps)}/s`);

/**
 * What the Rate says: the rate once two messages came in the window; "measuring…" before; "no messages" when nothing
 * came after NO_MESSAGES_AFTER_S; for a slow or latched topic, once the window is full, how many came in it.
 * @param {TopicStats | null} s @param {number} elapsedS  since this page began asking
 */
export function rateText(s, elapsedS) {
  if (!s) return m.inspect_measuring();
  if (!s.ok) return '—';
  if (s.messages >= 2) return formatRate(s.rate_hz);
  // Another page may have started measuring earlier: the window says how long the robot PC has been listening.
  const listened = Math.max(elapsedS, s.window_s);
  if (s.last_age_s < 0) return listened >= NO_MESSAGES_AFTER_S ? m.inspect_no_messages() : m.inspect_measuring();
  if (s.window_s >= STATS_WINDOW_S - 0.5) {
    const seconds = int(Math.round(s.window_s));
    return s.messages === 1 ? m.inspect_one_message_in_last({ seconds }) : m.inspect_no_messages_in_last({ seconds });
  }
  return m.inspect_measuring();
}

/**
 * What the Bandwidth says: bytes per second once a message came in the window.
 * @param {TopicStats | null} s @param {number} elapsedS
 */
export function bandwidthText(s, elapsedS) {
  if (!s) return m.inspect_measuring();
  if (!s.ok) return '—';
  if (s.messages >= 1) return formatBandwidth(s.bandwidth_bps);
  if (s.last_age_s < 0) return Math.max(elapsedS, s.window_s) >= NO_MESSAGES_AFTER_S ? m.inspect_no_messages() : m.inspect_measuring();
  return formatBandwidth(0);
}

/** The mean message size, "—" before any. @param {TopicStats | null} s */
export const meanSizeText = (s) => (s?.ok && s.messages >= 1 ? formatBytes(s.mean_bytes) : '—');

/**
 * How long ago a message came: "35 ms ago", "2.5 s ago", "3 min ago", "none received yet" (-1).
 * @param {number} ageS
 */
export function ageText(ageS) {
  if (typeof ageS !== 'number' || !Number.isFinite(ageS) || ageS < 0) return m.inspect_age_none();
  if (ageS < 1) return m.inspect_ago({ age: `${int(Math.round(ageS * 1000))} ms` });
  if (ageS < 59.95) return m.inspect_ago({ age: `${fmtFixed(ageS, 1)} s` });
  const min = Math.floor(ageS / 60);
  if (min < 120) return m.inspect_ago({ age: `${int(min)} min` });
  return m.inspect_ago({ age: `${int(Math.floor(min / 60))} h` });
}

/** Under the figures: "Over the last 10 s (as rostopic hz and bw)". @param {TopicStats | null} s */
export const windowText = (s) => (s?.ok && s.window_s > 0 ? m.inspect_window({ span: spanText(s.window_s) }) : '');

// ---- a topic's last message (echo) as a tree ----

/**
 * cell_msgs/TopicEcho's response.
 * @typedef {{ ok: boolean, message: string, type: string, json: string, age_s: number }} EchoAnswer
 */

/** The echo service's answer with every field of its type (age -1 when none). @param {any} r @returns {EchoAnswer} */
export function normaliseEcho(r) {
  const age = typeof r?.age_s === 'number' && Number.isFinite(r.age_s) && r.age_s >= 0 ? r.age_s : -1;
  return { ok: r?.ok === true, message: str(r?.message), type: str(r?.type), json: str(r?.json), age_s: age };
}

/** Why the echo's text is not JSON ('empty' is the page's own reason, in the user's language). @param {string} error */
export const echoErrorText = (error) => (error === 'empty' ? m.inspect_echo_empty() : error);

/**
 * The echo's JSON text, parsed; the raw text when it is not JSON (the page shows it as it came).
 * @param {any} json @returns {{ parsed: true, value: any } | { parsed: false, raw: string, error: string }}
 */
export function parseEcho(json) {
  const raw = typeof json === 'string' ? json : json === null || json === undefined ? '' : String(json);
  if (!raw.trim()) return { parsed: false, raw, error: 'empty' };
  try {
    return { parsed: true, value: JSON.parse(raw) };
  } catch (e) {
    return { parsed: false, raw, error: e instanceof Error ? e.message : String(e) };
  }
}

/** @typedef {'object' | 'array' | 'string' | 'number' | 'boolean' | 'null'} JsonKind */

/** @param {any} v @returns {JsonKind} */
export function jsonKind(v) {
  if (v === null || v === undefined) return 'null';
  if (Array.isArray(v)) return 'array';
  const t = typeof v;
  return t === 'object' ? 'object' : t === 'number' ? 'number' : t === 'boolean' ? 'boolean' : 'string';
}

/** A branch's children: an array's items by index, an object's fields in their order. @param {any} v */
export function jsonChildren(v) {
  if (Array.isArray(v)) return v.map((value, i) => ({ key: String(i), value }));
  if (v && typeof v === 'object') return Object.entries(v).map(([key, value]) => ({ key, value }));
  return [];
}

/** The robot PC's last item of a cut array: "… 97 more (100 items)" (or "... 97 more (100 items)"). */
const CUT_ITEM = /^(?:…|\.\.\.)\s*(\d+) more \((\d+) items?\)$/;

/**
 * An array the robot PC cut: how many items it had and how many came (null when not cut).
 * @param {any[]} a @returns {{ total: number, shown: number } | null}
 */
export function cutArray(a) {
  const last = a.length ? a[a.length - 1] : null;
  const hit = typeof last === 'string' ? CUT_ITEM.exec(last.trim()) : null;
  return hit ? { total: Number(hit[2]), shown: a.length - 1 } : null;
}

/** A branch's summary: "[100 items, first 16 shown]", "[3 items]", "{2 fields}". @param {any} v */
export function jsonSummary(v) {
  if (Array.isArray(v)) {
    const cut = cutArray(v);
    if (cut) return `[${m.inspect_json_cut({ items: m.inspect_n_items({ count: cut.total }), shown: int(cut.shown) })}]`;
    return `[${m.inspect_n_items({ count: v.length })}]`;
  }
  if (v && typeof v === 'object') return `{${m.inspect_n_fields({ count: Object.keys(v).length })}}`;
  return '';
}

/** A leaf as JSON writes it: strings quoted, null, numbers, booleans. @param {any} v */
export function jsonScalarText(v) {
  if (v === null || v === undefined) return 'null';
  if (typeof v === 'string') return JSON.stringify(v);
  return String(v);
}

// ---- diagnostics (the diagnostics aggregator's status tree) ----

/** A latched ~1 Hz array: nothing for this long means the robot PC stopped sending ("no update for N s"). */
export const DIAG_NO_UPDATE_S = 3;

/** @typedef {'ok' | 'warn' | 'error' | 'stale'} DiagLevelName */
/** @typedef {'ok' | 'warn' | 'danger' | 'neutral'} DiagTone */
/**
 * @typedef {object} DiagLevel
 * @property {DiagLevelName} name
 * @property {number} value  diagnostic_msgs/DiagnosticStatus' level
 * @property {string} upper  the level's ROS name ("OK", "WARN", "ERROR", "STALE")
 * @property {string} badge  what the row says (the name in the user's language)
 * @property {number} rank  how bad, for "worst first" (higher is worse)
 * @property {DiagTone} tone
 */

/**
 * diagnostic_msgs/DiagnosticStatus' levels. Worst first means error, then stale, then warn: an error is a known fault,
 * a stale status may hide one (its reporter went silent), a warning is a known lesser problem.
 */
export const DIAG_LEVELS = /** @type {readonly DiagLevel[]} */ (Object.freeze([
  { name: 'ok', value: 0, upper: 'OK', get badge() { return m.inspect_diag_ok_badge(); }, rank: 0, tone: 'ok' },
  { name: 'warn', value: 1, upper: 'WARN', get badge() { return m.inspect_diag_warn_badge(); }, rank: 1, tone: 'warn' },
  { name: 'error', value: 2, upper: 'ERROR', get badge() { return m.inspect_diag_error_badge(); }, rank: 3, tone: 'danger' },
  { name: 'stale', value: 3, upper: 'STALE', get badge() { return m.inspect_diag_stale_badge(); }, rank: 2, tone: 'neutral' },
].map((l) => Object.freeze(l))));

const DIAG_BY_NAME = new Map(DIAG_LEVELS.map((l) => [l.name, l]));

/**
 * A status level's name from the message's number (0 OK, 1 WARN, 2 ERROR, 3 STALE). Anything else (another number,
 * missing, not a number) is an error, as the robot PC reads it: an unknown level is not "fine".
 * @param {any} n @returns {DiagLevelName}
 */
export function diagLevelName(n) {
  const v = typeof n === 'number' ? n : typeof n === 'string' && /^\s*\d+\s*$/.test(n) ? Number(n) : NaN;
  return DIAG_LEVELS.find((l) => l.value === v)?.name ?? 'error';
}

/** A level by name: its text, rank and tone. @param {DiagLevelName} name @returns {DiagLevel} */
export const diagLevel = (name) => /** @type {DiagLevel} */ (DIAG_BY_NAME.get(name) ?? DIAG_BY_NAME.get('error'));

/**
 * One status in the page's shape.
 * @typedef {object} DiagStatus
 * @property {string} name  e.g. "vision: camera brightness"
 * @property {DiagLevelName} level
 * @property {string} message  a stale status keeps its last one
 * @property {string} hardware_id
 * @property {{ key: string, value: string }[]} values
 * @property {string} group  the part of the name before the first ": " ("other" when none)
 * @property {string} short  the name without the group ("camera brightness"; the whole name when it has no group)
 */

/** The group of statuses whose name has no "component: " part. */
export const DIAG_OTHER_GROUP = 'other';

/** A group's name as shown: the one without a component in the user's language. @param {string} name */
export const diagGroupText = (name) => (name === DIAG_OTHER_GROUP ? m.inspect_diag_other() : name);

/**
 * A status name's group and the rest: "vision: camera brightness" → { group: "vision", short: "camera brightness" }.
 * A name without ": " (or with nothing before or after it) goes in "other", whole.
 * @param {string} name @returns {{ group: string, short: string }}
 */
export function diagGroupOf(name) {
  const i = name.indexOf(': ');
  const group = i > 0 ? name.slice(0, i).trim() : '';
  const short = i > 0 ? name.slice(i + 2).trim() : '';
  return group && short ? { group, short } : { group: DIAG_OTHER_GROUP, short: name };
}

/**
 * A diagnostic_msgs/DiagnosticArray's statuses in the page's shape: every field of its type; one status per name
 * (the later one wins: the aggregator sends one, and the rows are keyed by name); unnamed ones left out.
 * @param {any} msg @returns {DiagStatus[]}
 */
export function normaliseDiagnostics(msg) {
  /** @type {Map<string, DiagStatus>} */
  const byName = new Map();
  for (const s of Array.isArray(msg?.status) ? msg.status : []) {
    const name = str(s?.name);
    if (!name) continue;
    const values = (Array.isArray(s?.values) ? s.values : []).map((/** @type {any} */ kv) => ({ key: str(kv?.key), value: str(kv?.value) }));
    byName.delete(name); // the later one's place, too
    byName.set(name, { name, level: diagLevelName(s?.level), message: str(s?.message), hardware_id: str(s?.hardware_id), values, ...diagGroupOf(name) });
  }
  return [...byName.values()];
}

/** @typedef {Record<DiagLevelName, number>} DiagCounts */

/** How many statuses at each level. @param {DiagStatus[]} statuses @returns {DiagCounts} */
export function diagCounts(statuses) {
  /** @type {DiagCounts} */
  const c = { ok: 0, warn: 0, error: 0, stale: 0 };
  for (const s of statuses) c[s.level]++;
  return c;
}

/** The summary line: "5 OK · 1 warning · 0 errors · 1 stale". @param {DiagCounts} c */
export const diagSummaryText = (c) =>
  `${int(c.ok)} OK · ${m.inspect_n_warnings({ count: c.warn })} · ${m.inspect_n_errors({ count: c.error })} · ${m.inspect_n_stale({ count: c.stale })}`;

/**
 * The worst of some levels ('ok' for none).
 * @param {Iterable<DiagLevelName>} levels @returns {DiagLevelName}
 */
export function worstDiagLevel(levels) {
  let worst = diagLevel('ok');
  for (const l of levels) if (diagLevel(l).rank > worst.rank) worst = diagLevel(l);
  return worst.name;
}

/** Worst level first, then by name. @param {DiagStatus} a @param {DiagStatus} b */
export const compareDiag = (a, b) => diagLevel(b.level).rank - diagLevel(a.level).rank || (a.name < b.name ? -1 : a.name > b.name ? 1 : 0);

/** @typedef {{ name: string, level: DiagLevelName, statuses: DiagStatus[] }} DiagGroup */

/**
 * The statuses as a tree of groups (by the part of the name before ": "): in each group the worst first, then by
 * name; the groups the same way by their worst status, then by name. The input is left as it is.
 * @param {DiagStatus[]} statuses @returns {DiagGroup[]}
 */
export function groupDiagnostics(statuses) {
  /** @type {Map<string, DiagStatus[]>} */
  const groups = new Map();
  for (const s of statuses) {
    const list = groups.get(s.group);
    if (list) list.push(s);
    else groups.set(s.group, [s]);
  }
  return [...groups].map(([name, list]) => ({ name, level: worstDiagLevel(list.map((s) => s.level)), statuses: list.sort(compareDiag) }))
    .sort((a, b) => diagLevel(b.level).rank - diagLevel(a.level).rank || (a.name < b.name ? -1 : a.name > b.name ? 1 : 0));
}

/** @typedef {'all' | 'problems'} DiagShow */

/** The "Show" choices (label: in the user's language). */
export const DIAG_SHOW = /** @type {readonly { id: DiagShow, label: string }[]} */ (Object.freeze([
  { id: 'all', get label() { return m.inspect_diag_show_all(); } },
  { id: 'problems', get label() { return m.inspect_diag_show_problems(); } },
].map((o) => Object.freeze(o))));

/**
 * The statuses the filters let through: "problems" keeps WARN, ERROR and STALE; the text keeps those whose name,
 * message or hardware id contains every word of it (any case). Order kept.
 * @param {DiagStatus[]} statuses @param {{ show: DiagShow, text: string }} f @returns {DiagStatus[]}
 */
export function filterDiagnostics(statuses, f) {
  const w = words(f.text);
  return statuses.filter((s) => {
    if (f.show === 'problems' && s.level === 'ok') return false;
    if (!w.length) return true;
    const hay = `${s.name} ${s.message} ${s.hardware_id}`.toLowerCase();
    return w.every((x) => hay.includes(x));
  });
}

/**
 * How old the last array is: "updated just now", "updated 2 s ago", and from DIAG_NO_UPDATE_S on "no update for 5 s"
 * ("no update for 3 min" later); '' before any. `stale` from DIAG_NO_UPDATE_S on.
 * @param {number | null} atMs  when the last array came @param {number} nowMs @returns {{ text: string, stale: boolean }}
 */
export function diagAgeText(atMs, nowMs) {
  if (atMs === null || !Number.isFinite(atMs)) return { text: '', stale: false };
  const s = Math.max(0, Math.floor((nowMs - atMs) / 1000));
  if (s < DIAG_NO_UPDATE_S) return { text: s < 1 ? m.inspect_diag_updated_now() : m.inspect_diag_updated_ago({ age: `${int(s)} s` }), stale: false };
  if (s < 120) return { text: m.inspect_diag_no_update({ age: `${int(s)} s` }), stale: true };
  const min = Math.floor(s / 60);
  return { text: m.inspect_diag_no_update({ age: min < 120 ? `${int(min)} min` : `${int(Math.floor(min / 60))} h` }), stale: true };
}
