/**
 * The recorder (flight recorder) feature's plain logic (no Svelte): the API calls, the ROS names, and everything
 * the page computes: the list's texts, the timeline's segments, ticks and colours, the events list, the status
 * line while a recording waits for its after-seconds. Tests import it directly.
 *
 * API (bff/src/features/recorder): GET /api/recorder/recordings -> { recordings, can_delete } (newest first),
 * GET /api/recorder/recordings/:name -> the recording with its window, topics and timeline,
 * GET /api/recorder/recordings/:name/file -> the MCAP file (a download), DELETE /api/recorder/recordings/:name.
 * ROS: /cell/recorder/state (cell_msgs/RecorderState, latched), /cell/recorder/save (std_srvs/Trigger).
 * Texts come from messages/recorder, numbers in the user's locale.
 */
import { m } from '$lib/paraglide/messages.js';
import { fmtNumber } from '$lib/core/i18n.js';
import { request } from '../../core/api.js';
import { formatBytes, formatDate } from '../database/logic.js';

export { formatBytes, formatDate };

export const FEATURE_ID = 'recorder';

export const NAMES = Object.freeze({
  state: { topic: '/cell/recorder/state', type: 'cell_msgs/RecorderState' },
  save: { service: '/cell/recorder/save', type: 'std_srvs/Trigger' },
});

/** The cell file's defaults (config/features/recorder.schema.json) when /api/config does not say. */
export const DEFAULT_BEFORE_S = 120;
export const DEFAULT_AFTER_S = 10;

/**
 * One recording as GET /api/recorder/recordings lists it. One whose details are unknown (no sidecar) has
 * reason '', alarms [], messages 0, duration_s 0 and at_ms = the file's mtime.
 * @typedef {object} Recording
 * @property {string} name  the file name (e.g. "20261126T140512.123Z-alarm-robot-protective-stop.mcap")
 * @property {number} at_ms  the alarm's (or the save request's) time, ms since the epoch
 * @property {string} reason  "alarm robot.protective_stop: Robot protective stop", "saved by hand", or ''
 * @property {number} size  bytes
 * @property {number} duration_s
 * @property {number} messages
 * @property {string[]} alarms  alarm ids
 */

/** @typedef {{ t_ms: number, text: string }} Change */
/** @typedef {{ id: string, title: string, changes: Change[] }} Lane  id: 'alarms' | 'process' | 'mode' */
/** @typedef {{ topic: string, type: string, count: number }} TopicInfo */
/**
 * GET /api/recorder/recordings/:name: the recording, its window, its topics and its timeline. Each lane's value
 * holds from one change to the next (the last one until end_ms).
 * @typedef {Recording & { start_ms: number, end_ms: number, topics: TopicInfo[], timeline: { lanes: Lane[] } }} RecordingDetail
 */

const enc = encodeURIComponent;

export const recorderApi = {
  list: () => request('GET', '/api/recorder/recordings'),
  /** @param {string} name */
  detail: (name) => request('GET', `/api/recorder/recordings/${enc(name)}`),
  /** @param {string} name */
  remove: (name) => request('DELETE', `/api/recorder/recordings/${enc(name)}`),
  /** The download's URL (a plain link: the browser downloads the attachment). @param {string} name */
  fileUrl: (name) => `/api/recorder/recordings/${enc(name)}/file`,
};

// ---- numbers and times ----

const MINUS = '\u2212';

/** @param {any} v */
const num = (v) => (typeof v === 'number' && Number.isFinite(v) ? v : null);

/** A number with one decimal at most ("120", "1.5"; "1,5" in Spanish). @param {number} v */
const tenths = (v) => fmtNumber(v, { maximumFractionDigits: 1, useGrouping: false });

/** "120 s", "1.5 s" (one decimal at most). @param {number} s */
const seconds = (s) => `${tenths(s)} s`;

/**
 * A time relative to the alarm, to a tenth of a second: "−3.2 s", "0 s", "+10 s".
 * @param {number} deltaMs
 */
export function formatRelative(deltaMs) {
  if (typeof deltaMs !== 'number' || !Number.isFinite(deltaMs)) return '—';
  const n = Math.round(Math.abs(deltaMs) / 100);
  if (n === 0) return '0 s';
  return `${deltaMs < 0 ? MINUS : '+'}${tenths(n / 10)} s`;
}

/** "9.5 s", "2 min 10 s", "1 h 5 min"; '—' when unknown or negative. @param {number | null | undefined} s */
export function formatDuration(s) {
  if (typeof s !== 'number' || !Number.isFinite(s) || s < 0) return '—';
  if (s < 60) return seconds(s);
  const total = Math.round(s);
  const h = Math.floor(total / 3600), min = Math.floor((total % 3600) / 60), sec = total % 60;
  const n = (/** @type {number} */ v) => fmtNumber(v);
  if (h > 0) return min ? `${n(h)} h ${n(min)} min` : `${n(h)} h`;
  return sec ? `${n(min)} min ${n(sec)} s` : `${n(min)} min`;
}

/** A ROS time ({secs, nsecs}, or {sec, nanosec}) in ms since the epoch; null when unset (0). @param {any} t */
export function rosTimeMs(t) {
  if (!t || typeof t !== 'object') return null;
  const ms = Number(t.secs ?? t.sec ?? 0) * 1000 + Number(t.nsecs ?? t.nanosec ?? 0) / 1e6;
  return Number.isFinite(ms) && ms > 0 ? ms : null;
}

// ---- the recorder node's state ----

/**
 * @typedef {object} RecorderStateView
 * @property {string} pending  why the recording waiting for its after-seconds is made, '' none
 * @property {number | null} pendingUntilMs
 * @property {string} lastSaved  the newest file's name, '' none
 * @property {string} error  the last save error, '' none
 * @property {number} savedCount
 * @property {string} key  changes whenever a recording was saved: the page then reloads the list
 */

/** cell_msgs/RecorderState as the page uses it. @param {any} msg @returns {RecorderStateView} */
export function stateView(msg) {
  const str = (/** @type {any} */ v) => (typeof v === 'string' ? v.trim() : '');
  const lastSaved = str(msg?.last_saved);
  const savedCount = Number(msg?.saved_count) || 0;
  return {
    pending: str(msg?.pending),
    pendingUntilMs: rosTimeMs(msg?.pending_until),
    lastSaved,
    error: str(msg?.error),
    savedCount,
    key: `${savedCount}|${lastSaved}`,
  };
}

/**
 * The status line while a recording waits for its after-seconds: "Saving a recording (<reason>) in 8 s"; the
 * seconds left are rounded up and never negative ("… now" once the time is over). '' when nothing is pending.
 * @param {RecorderStateView | null | undefined} st @param {number} nowMs
 */
export function pendingText(st, nowMs) {
  if (!st?.pending) return '';
  const reason = st.pending;
  if (st.pendingUntilMs === null) return m.recorder_pending_soon({ reason });
  const left = Math.max(0, Math.ceil((st.pendingUntilMs - nowMs) / 1000));
  return left > 0 ? m.recorder_pending_in({ reason, seconds: fmtNumber(left) }) : m.recorder_pending_now({ reason });
}

/** The role=alert text for the node's last save error ('' none). @param {RecorderStateView | null | undefined} st */
export const saveErrorText = (st) => (st?.error ? m.recorder_save_error({ error: st.error }) : '');

/**
 * What a recording holds, from the cell file's section (/api/config features.recorder):
 * "Each error alarm saves the 120 s before it and the 10 s after it."
 * @param {any} section
 */
export function windowText(section) {
  const before = num(section?.before_s) ?? DEFAULT_BEFORE_S;
  const after = num(section?.after_s) ?? DEFAULT_AFTER_S;
  const b = seconds(before), a = seconds(after);
  if (section?.severity === 'warning') {
    return after > 0 ? m.recorder_window_warning({ before: b, after: a }) : m.recorder_window_warning_before({ before: b });
  }
  return after > 0 ? m.recorder_window_error({ before: b, after: a }) : m.recorder_window_error_before({ before: b });
}

// ---- the list ----

/** Made by an alarm (else by hand, or unknown). @param {Recording} r */
export const isAlarmRecording = (r) =>
  (Array.isArray(r?.alarms) && r.alarms.length > 0) || /^alarm\b/i.test(String(r?.reason ?? ''));

/** Whether the recorder wrote what this recording holds (its sidecar); else only the file is known. @param {Recording} r */
export const detailsKnown = (r) => !!r?.reason || (Number(r?.messages) || 0) > 0 || (Number(r?.duration_s) || 0) > 0;

/**
 * @typedef {object} RecordingView
 * @property {string} name
 * @property {string} when  "22 Nov 2026, 14:03:21"
 * @property {string} why  the reason, or "Reason unknown"
 * @property {string} duration
 * @property {string} size
 * @property {string} messages  "1,234 messages", '' when unknown
 * @property {boolean} known
 * @property {boolean} isAlarm
 * @property {string} marker  the timeline's label at at_ms: "Alarm" or "Saved" (in the user's language)
 */

/** The timeline's label at the alarm (or the save request). @param {boolean} isAlarm */
export const markerText = (isAlarm) => (isAlarm ? m.recorder_marker_alarm() : m.recorder_marker_saved());

/** One row of the list. @param {Recording} r @returns {RecordingView} */
export function recordingView(r) {
  const known = detailsKnown(r);
  const n = Number(r?.messages) || 0;
  const isAlarm = isAlarmRecording(r);
  return {
    name: r.name,
    when: formatDate(r.at_ms),
    why: r.reason || m.recorder_reason_unknown(),
    duration: known ? formatDuration(r.duration_s) : '—',
    size: formatBytes(r.size),
    messages: known ? m.recorder_n_messages({ count: n, n: fmtNumber(n) }) : '',
    known,
    isAlarm,
    marker: markerText(isAlarm),
  };
}

/**
 * Which recording to show: the one picked by hand while it is still listed, else the newest (the list is newest
 * first), '' when there are none.
 * @param {Recording[]} list @param {string} current @param {boolean} pinned  picked by hand
 */
export function chooseSelected(list, current, pinned) {
  if (pinned && current && list.some((r) => r.name === current)) return current;
  return list[0]?.name ?? '';
}

/** The confirmation before a delete. @param {RecordingView} v */
export function deleteQuestion(v) {
  return {
    title: m.recorder_delete_title({ when: v.when }),
    message: m.recorder_delete_message({ name: v.name, size: v.size }),
  };
}

// ---- the timeline ----

/** @typedef {'danger' | 'ok' | 'warn' | 'idle' | 'neutral' | 'none'} Tone */

/**
 * The colour of a lane's value (the page's class is `tone-<tone>`; the text is always shown too):
 * alarms red while any is active; process running green, error red, paused (pausing, stopping) amber, idle grey;
 * operation mode alarm red, running green; anything else neutral; no value 'none'.
 * @param {string} laneId @param {string} text @returns {Tone}
 */
export function laneTone(laneId, text) {
  const t = String(text ?? '').trim();
  if (!t) return 'none';
  if (laneId === 'alarms') return 'danger';
  const word = (t.split('·')[0].trim().toLowerCase().split(/[\s:]+/)[0]) ?? '';
  if (laneId === 'process') {
    if (word === 'running') return 'ok';
    if (word === 'error') return 'danger';
    if (word === 'paused' || word === 'pausing' || word === 'stopping') return 'warn';
    if (word === 'idle') return 'idle';
    return 'neutral';
  }
  if (laneId === 'mode') {
    if (word === 'alarm') return 'danger';
    if (word === 'running') return 'ok';
  }
  return 'neutral';
}

/**
 * @typedef {object} Segment
 * @property {number} from_ms
 * @property {number} to_ms
 * @property {number} left  % of the window
 * @property {number} width  % of the window
 * @property {string} text
 * @property {Tone} tone
 */

/** Does the recording have a window to draw? @param {{ start_ms?: number, end_ms?: number } | null | undefined} d */
export const hasWindow = (d) => {
  const s = num(d?.start_ms), e = num(d?.end_ms);
  return s !== null && e !== null && e > s;
};

/**
 * A lane as segments of [startMs, endMs]: each value from its change to the next (the last to endMs), clamped to
 * the window, zero-width ones dropped, neighbours with the same value joined.
 * @param {Lane} lane @param {number} startMs @param {number} endMs @returns {Segment[]}
 */
export function laneSegments(lane, startMs, endMs) {
  const span = endMs - startMs;
  if (!(span > 0)) return [];
  const changes = (Array.isArray(lane?.changes) ? lane.changes : [])
    .filter((c) => c && num(c.t_ms) !== null)
    .slice()
    .sort((a, b) => a.t_ms - b.t_ms);
  /** @type {Segment[]} */
  const out = [];
  changes.forEach((c, i) => {
    const next = changes[i + 1];
    const from = Math.max(startMs, c.t_ms);
    const to = Math.min(endMs, next ? next.t_ms : endMs);
    if (!(to > from)) return;
    const text = typeof c.text === 'string' ? c.text : '';
    const last = out[out.length - 1];
    if (last && last.text === text && last.to_ms === from) {
      last.to_ms = to;
      last.width = ((to - last.from_ms) / span) * 100;
      return;
    }
    out.push({ from_ms: from, to_ms: to, left: ((from - startMs) / span) * 100, width: ((to - from) / span) * 100, text, tone: laneTone(lane.id, text) });
  });
  return out;
}

/** Where a time is in the window, in %, clamped to 0..100. @param {number} t @param {number} startMs @param {number} endMs */
export function percentAt(t, startMs, endMs) {
  const span = endMs - startMs;
  if (!(span > 0)) return 0;
  return Math.min(100, Math.max(0, ((t - startMs) / span) * 100));
}

/** How a label at `left` % sits on it: its start at the left edge, its end at the right edge, else centred. @param {number} left */
export const labelAlign = (left) => (left < 4 ? 'start' : left > 96 ? 'end' : 'middle');

/** @typedef {{ rel_ms: number, left: number, label: string, align: 'start' | 'middle' | 'end' }} Tick */

/** Tick spacings in s, the smallest that gives at most the wanted number of ticks wins. */
export const TICK_STEPS_S = Object.freeze([0.5, 1, 2, 5, 10, 15, 20, 30, 60, 120, 300, 600, 900, 1800, 3600]);

/** An axis label's width in px: about this much per character (0.78rem tabular digits) plus a gap. */
export const TICK_CHAR_PX = 7.5;
export const TICK_PAD_PX = 10;

/**
 * Where a label sits on the axis, in % of its width: [from, to].
 * @param {number} left @param {string} label @param {'start' | 'middle' | 'end'} align @param {number} widthPx
 */
export function labelExtent(left, label, align, widthPx) {
  const w = ((label.length * TICK_CHAR_PX + TICK_PAD_PX) / widthPx) * 100;
  if (align === 'start') return [left, left + w];
  if (align === 'end') return [left - w, left];
  return [left - w / 2, left + w / 2];
}

/**
 * The time axis, in s relative to the alarm: "−120 s", "−60 s", "0", "+10 s". Candidates in this order: the
 * alarm (0), the window's two ends, then round steps (about one per 64 px, at most 6); each is kept only when
 * its label does not overlap one already kept on an axis `widthPx` wide (labels at the ends are aligned to them).
 * @param {number} startMs @param {number} endMs @param {number} atMs @param {number} [widthPx]  the axis's width
 * @returns {Tick[]}
 */
export function axisTicks(startMs, endMs, atMs, widthPx = 320) {
  const span = endMs - startMs;
  if (!(span > 0) || !Number.isFinite(atMs)) return [];
  const width = Math.max(64, Number(widthPx) || 320);
  const wanted = Math.max(1, Math.min(6, Math.floor(width / 64)));
  const stepS = TICK_STEPS_S.find((s) => span / 1000 / s <= wanted) ?? TICK_STEPS_S[TICK_STEPS_S.length - 1];
  const stepMs = stepS * 1000;
  /** @type {number[]} */
  const candidates = [];
  if (atMs >= startMs && atMs <= endMs) candidates.push(atMs);
  candidates.push(startMs, endMs);
  for (let k = Math.ceil((startMs - atMs) / stepMs); atMs + k * stepMs <= endMs; k++) candidates.push(atMs + k * stepMs);
  /** @type {(Tick & { extent: number[] })[]} */
  const kept = [];
  for (const t of candidates) {
    const left = percentAt(t, startMs, endMs);
    const rel = t - atMs;
    const label = Math.abs(rel) < 50 ? '0' : formatRelative(rel);
    const align = labelAlign(left);
    const [a, b] = labelExtent(left, label, align, width);
    if (kept.some((k) => a < k.extent[1] && b > k.extent[0])) continue;
    kept.push({ rel_ms: rel, left, label, align, extent: [a, b] });
  }
  return kept.sort((x, y) => x.left - y.left).map(({ extent, ...t }) => t);
}

/**
 * @typedef {object} TimelineEvent
 * @property {number} t_ms
 * @property {string} rel  "−3.2 s" from the alarm
 * @property {string} lane  the lane's id
 * @property {string} laneTitle
 * @property {string} text  the value ("" none)
 * @property {string} label  what the list says: the value, or "No active alarm" / "No value"
 * @property {Tone} tone
 */

/** What the events list says for a value. @param {string} laneId @param {string} text */
export const eventLabel = (laneId, text) => (text ? text : laneId === 'alarms' ? m.recorder_no_active_alarm() : m.recorder_no_value());

/**
 * A lane's title in the user's language (the recorder names its three lanes in English); another lane by its own.
 * @param {{ id: string, title?: string }} lane
 */
export function laneTitle(lane) {
  switch (lane?.id) {
    case 'alarms': return m.recorder_lane_alarms();
    case 'process': return m.recorder_lane_process();
    case 'mode': return m.recorder_lane_mode();
    default: return lane?.title || lane?.id || '';
  }
}

/**
 * Every change of every lane, by time (lanes in their order at the same time): the text record of the timeline.
 * @param {RecordingDetail} d @returns {TimelineEvent[]}
 */
export function timelineEvents(d) {
  const lanes = Array.isArray(d?.timeline?.lanes) ? d.timeline.lanes : [];
  /** @type {(TimelineEvent & { order: number })[]} */
  const all = [];
  lanes.forEach((lane, li) => {
    for (const c of Array.isArray(lane?.changes) ? lane.changes : []) {
      if (!c || num(c.t_ms) === null) continue;
      const text = typeof c.text === 'string' ? c.text : '';
      all.push({
        t_ms: c.t_ms, rel: formatRelative(c.t_ms - d.at_ms), lane: lane.id, laneTitle: laneTitle(lane),
        text, label: eventLabel(lane.id, text), tone: laneTone(lane.id, text), order: li,
      });
    }
  });
  return all
    .sort((a, b) => a.t_ms - b.t_ms || a.order - b.order)
    .map(({ order, ...e }) => e);
}

/**
 * The timeline figure's accessible summary.
 * @param {RecordingDetail} d
 */
export function timelineSummary(d) {
  const lanes = Array.isArray(d?.timeline?.lanes) ? d.timeline.lanes : [];
  const counts = lanes.map((l) => {
    const n = Array.isArray(l.changes) ? l.changes.length : 0;
    return m.recorder_summary_lane({ count: n, lane: laneTitle(l), n: fmtNumber(n) });
  });
  return [
    m.recorder_summary_at({ marker: markerText(isAlarmRecording(d)), when: formatDate(d.at_ms) }),
    ...(hasWindow(d) ? [m.recorder_summary_window({ from: formatRelative(d.start_ms - d.at_ms), to: formatRelative(d.end_ms - d.at_ms) })] : []),
    ...(counts.length ? [`${counts.join(', ')}.`] : []),
    m.recorder_summary_tail(),
  ].join(' ');
}

/** Topics, most messages first, then by name. @param {TopicInfo[] | undefined} topics @returns {TopicInfo[]} */
export function topicRows(topics) {
  return (Array.isArray(topics) ? topics : [])
    .filter((t) => t && typeof t.topic === 'string')
    .slice()
    .sort((a, b) => (Number(b.count) || 0) - (Number(a.count) || 0) || a.topic.localeCompare(b.topic));
}
