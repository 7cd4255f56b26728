import { describe, it, expect, vi, afterEach } from 'vitest';
import {
  recorderApi, NAMES, formatRelative, formatDuration, rosTimeMs, stateView, pendingText, saveErrorText, windowText,
  isAlarmRecording, detailsKnown, recordingView, chooseSelected, deleteQuestion, laneTone, laneSegments, hasWindow,
  percentAt, labelAlign, labelExtent, axisTicks, timelineEvents, eventLabel, timelineSummary, topicRows, formatDate, formatBytes,
} from '../../../src/lib/features/recorder/logic.js';

const M = '\u2212';
const AT = Date.UTC(2026, 10, 26, 14, 5, 12, 123);
const NAME = '20261126T140512.123Z-alarm-robot-protective-stop-robot-protective-stop.mcap';

/** @type {import('../../../src/lib/features/recorder/logic.js').Recording} */
const ALARM_REC = {
  name: NAME, at_ms: AT, reason: 'alarm robot.protective_stop: Robot protective stop', size: 2 * 1024 * 1024,
  duration_s: 130, messages: 1234, alarms: ['robot.protective_stop'],
};
/** @type {import('../../../src/lib/features/recorder/logic.js').Recording} */
const UNKNOWN_REC = { name: 'old.mcap', at_ms: AT - 3600e3, reason: '', size: 512, duration_s: 0, messages: 0, alarms: [] };

/** @type {import('../../../src/lib/features/recorder/logic.js').RecordingDetail} */
const DETAIL = {
  ...ALARM_REC,
  start_ms: AT - 120000,
  end_ms: AT + 10000,
  topics: [
    { topic: '/joint_states', type: 'sensor_msgs/JointState', count: 65000 },
    { topic: '/cell/alarms/list', type: 'cell_msgs/AlarmList', count: 130 },
    { topic: '/cell/mode', type: 'cell_msgs/OperationMode', count: 130 },
  ],
  timeline: {
    lanes: [
      { id: 'alarms', title: 'Alarms', changes: [{ t_ms: AT - 120000, text: '' }, { t_ms: AT - 100, text: 'robot.protective_stop: Robot protective stop' }] },
      { id: 'process', title: 'Process', changes: [
        { t_ms: AT - 120000, text: 'running · Move to part 2 (approach)' },
        { t_ms: AT - 3200, text: 'error · Move failed: protective stop' },
      ] },
      { id: 'mode', title: 'Operation mode', changes: [{ t_ms: AT - 120000, text: 'running' }, { t_ms: AT - 100, text: 'alarm' }] },
    ],
  },
};

afterEach(() => vi.unstubAllGlobals());

describe('the API', () => {
  it('list, detail and delete go to /api/recorder/recordings with the name encoded; the file is a plain URL', async () => {
    /** @type {{ method: string, url: string }[]} */
    const calls = [];
    vi.stubGlobal('fetch', vi.fn(async (/** @type {string} */ url, /** @type {RequestInit} */ init) => {
      calls.push({ method: init?.method ?? 'GET', url });
      if (init?.method === 'DELETE') return new Response(JSON.stringify({ error: 'your role may not delete recordings' }), { status: 403 });
      return new Response(JSON.stringify({ recordings: [ALARM_REC], can_delete: true }), { status: 200 });
    }));
    const list = await recorderApi.list();
    expect(list).toMatchObject({ kind: 'ok', data: { can_delete: true } });
    await recorderApi.detail('a b/c#?.mcap');
    const del = await recorderApi.remove(NAME);
    expect(del).toMatchObject({ kind: 'forbidden', error: 'your role may not delete recordings' });
    expect(calls).toEqual([
      { method: 'GET', url: '/api/recorder/recordings' },
      { method: 'GET', url: '/api/recorder/recordings/a%20b%2Fc%23%3F.mcap' },
      { method: 'DELETE', url: `/api/recorder/recordings/${NAME}` },
    ]);
    expect(recorderApi.fileUrl('a b/c.mcap')).toBe('/api/recorder/recordings/a%20b%2Fc.mcap/file');
    expect(NAMES.state).toEqual({ topic: '/cell/recorder/state', type: 'cell_msgs/RecorderState' });
    expect(NAMES.save).toEqual({ service: '/cell/recorder/save', type: 'std_srvs/Trigger' });
  });
});

describe('times', () => {
  it('relative to the alarm, to a tenth of a second, with a real minus sign', () => {
    expect(formatRelative(-3200)).toBe(`${M}3.2 s`);
    expect(formatRelative(0)).toBe('0 s');
    expect(formatRelative(-40)).toBe('0 s');
    expect(formatRelative(49)).toBe('0 s');
    expect(formatRelative(10000)).toBe('+10 s');
    expect(formatRelative(-120000)).toBe(`${M}120 s`);
    expect(formatRelative(-119960)).toBe(`${M}120 s`);
    expect(formatRelative(250)).toBe('+0.3 s');
    expect(formatRelative(-250)).toBe(`${M}0.3 s`);
    expect(formatRelative(NaN)).toBe('—');
  });

  it('durations', () => {
    expect(formatDuration(9.46)).toBe('9.5 s');
    expect(formatDuration(0)).toBe('0 s');
    expect(formatDuration(60)).toBe('1 min');
    expect(formatDuration(130.2)).toBe('2 min 10 s');
    expect(formatDuration(3900)).toBe('1 h 5 min');
    expect(formatDuration(7200)).toBe('2 h');
    expect(formatDuration(-1)).toBe('—');
    expect(formatDuration(undefined)).toBe('—');
  });

  it('ROS times', () => {
    expect(rosTimeMs({ secs: 10, nsecs: 500000000 })).toBe(10500);
    expect(rosTimeMs({ sec: 1, nanosec: 0 })).toBe(1000);
    expect(rosTimeMs({ secs: 0, nsecs: 0 })).toBeNull();
    expect(rosTimeMs(null)).toBeNull();
  });
});

describe('the recorder node state', () => {
  const now = 1_800_000_000_000;
  const msg = (/** @type {any} */ o = {}) => ({ pending: '', pending_until: { secs: 0, nsecs: 0 }, last_saved: '', error: '', saved_count: 0, ...o });

  it('the status line counts the seconds left down, rounded up, never negative', () => {
    const reason = 'alarm robot.protective_stop: Robot protective stop';
    const st = stateView(msg({ pending: reason, pending_until: { secs: (now + 8200) / 1000, nsecs: 0 } }));
    expect(st.pending).toBe(reason);
    expect(pendingText(st, now)).toBe(`Saving a recording (${reason}) in 9 s`);
    expect(pendingText(st, now + 8000)).toBe(`Saving a recording (${reason}) in 1 s`);
    expect(pendingText(st, now + 8200)).toBe(`Saving a recording (${reason}) now`);
    expect(pendingText(st, now + 60000)).toBe(`Saving a recording (${reason}) now`);
    expect(pendingText(stateView(msg({ pending: 'saved by hand' })), now)).toBe('Saving a recording (saved by hand) soon');
    expect(pendingText(stateView(msg()), now)).toBe('');
    expect(pendingText(null, now)).toBe('');
  });

  it('its key changes with every save (the page then reloads the list); the error as an alert text', () => {
    const a = stateView(msg({ last_saved: 'a.mcap', saved_count: 1 }));
    const b = stateView(msg({ last_saved: 'b.mcap', saved_count: 2 }));
    const sameAgain = stateView(msg({ last_saved: 'a.mcap', saved_count: 1, pending: 'x' }));
    expect(a.key).not.toBe(b.key);
    expect(a.key).toBe(sameAgain.key);
    // The same file name again (a restart of the node) still counts as new by its count.
    expect(stateView(msg({ last_saved: 'a.mcap', saved_count: 3 })).key).not.toBe(a.key);
    expect(saveErrorText(stateView(msg({ error: 'disk full' })))).toBe('The last recording could not be saved: disk full');
    expect(saveErrorText(a)).toBe('');
    expect(stateView(undefined)).toMatchObject({ pending: '', pendingUntilMs: null, lastSaved: '', error: '', savedCount: 0 });
  });

  it('what a recording holds, from the cell file section', () => {
    expect(windowText({ before_s: 120, after_s: 10 })).toBe('Each error alarm saves the 120 s before it and the 10 s after it.');
    expect(windowText({ before_s: 30.5, after_s: 0 })).toBe('Each error alarm saves the 30.5 s before it.');
    expect(windowText({ before_s: 60, after_s: 5, severity: 'warning' })).toBe('Each error or warning alarm saves the 60 s before it and the 5 s after it.');
    expect(windowText(undefined)).toBe('Each error alarm saves the 120 s before it and the 10 s after it.');
  });
});

describe('the list', () => {
  it('a row: when, why, duration, size and messages; unknown details say so', () => {
    const v = recordingView(ALARM_REC);
    expect(v).toMatchObject({
      name: NAME, when: formatDate(AT), why: 'alarm robot.protective_stop: Robot protective stop', duration: '2 min 10 s',
      size: '2.0 MB', messages: '1,234 messages', known: true, isAlarm: true, marker: 'Alarm',
    });
    expect(v.when).toMatch(/^\d{1,2} Nov 2026, \d\d:\d\d:\d\d$/);
    const u = recordingView(UNKNOWN_REC);
    expect(u).toMatchObject({ why: 'Reason unknown', duration: '—', size: '512 B', messages: '', known: false, isAlarm: false, marker: 'Saved' });
    const byHand = recordingView({ ...UNKNOWN_REC, reason: 'saved by hand', duration_s: 130, messages: 1 });
    expect(byHand).toMatchObject({ why: 'saved by hand', messages: '1 message', isAlarm: false, marker: 'Saved', known: true });
    expect(isAlarmRecording({ ...UNKNOWN_REC, reason: 'alarm x: y' })).toBe(true);
    expect(detailsKnown(UNKNOWN_REC)).toBe(false);
    expect(formatBytes(2048)).toBe('2.0 KB');
  });

  it('the recording shown: the newest, or the one picked by hand while it is listed', () => {
    const list = [{ ...ALARM_REC, name: 'new.mcap' }, { ...ALARM_REC, name: 'mid.mcap' }, UNKNOWN_REC];
    expect(chooseSelected(list, '', false)).toBe('new.mcap');
    expect(chooseSelected(list, 'mid.mcap', false)).toBe('new.mcap');
    expect(chooseSelected(list, 'mid.mcap', true)).toBe('mid.mcap');
    expect(chooseSelected(list, 'gone.mcap', true)).toBe('new.mcap');
    expect(chooseSelected([], 'mid.mcap', true)).toBe('');
  });

  it('the delete confirmation names the recording and the file', () => {
    const q = deleteQuestion(recordingView(ALARM_REC));
    expect(q.title).toBe(`Delete the recording of ${formatDate(AT)}?`);
    expect(q.message).toBe(`${NAME} (2.0 MB) is deleted from the robot PC. This cannot be undone.`);
  });
});

describe('the timeline', () => {
  it('colours per lane value', () => {
    expect(laneTone('alarms', 'robot.protective_stop: Robot protective stop')).toBe('danger');
    expect(laneTone('alarms', '')).toBe('none');
    expect(laneTone('process', 'running · Move to part 2 (approach)')).toBe('ok');
    expect(laneTone('process', 'error · Move failed: ...')).toBe('danger');
    expect(laneTone('process', 'paused · Move to part 2')).toBe('warn');
    expect(laneTone('process', 'Stopping')).toBe('warn');
    expect(laneTone('process', 'idle')).toBe('idle');
    expect(laneTone('process', 'unknown')).toBe('neutral');
    expect(laneTone('process', '  ')).toBe('none');
    expect(laneTone('mode', 'alarm')).toBe('danger');
    expect(laneTone('mode', 'running')).toBe('ok');
    expect(laneTone('mode', 'manual')).toBe('neutral');
    expect(laneTone('mode', 'paused')).toBe('neutral');
    expect(laneTone('other', 'x')).toBe('neutral');
  });

  it('segments: from each change to the next (the last to the end), in % of the window', () => {
    const segs = laneSegments(DETAIL.timeline.lanes[1], DETAIL.start_ms, DETAIL.end_ms);
    expect(segs.length).toBe(2);
    expect(segs[0]).toMatchObject({ from_ms: AT - 120000, to_ms: AT - 3200, left: 0, text: 'running · Move to part 2 (approach)', tone: 'ok' });
    expect(segs[0].width).toBeCloseTo((116.8 / 130) * 100, 6);
    expect(segs[1]).toMatchObject({ from_ms: AT - 3200, to_ms: AT + 10000, tone: 'danger' });
    expect(segs[1].left).toBeCloseTo((116.8 / 130) * 100, 6);
    expect(segs[1].left + segs[1].width).toBeCloseTo(100, 6);
  });

  it('segments are clamped to the window; zero-width ones dropped; equal neighbours joined; unsorted input sorted', () => {
    const lane = { id: 'mode', title: 'Operation mode', changes: [
      { t_ms: 1500, text: 'alarm' },
      { t_ms: 0, text: 'manual' }, // before the window: carried in
      { t_ms: 500, text: 'running' },
      { t_ms: 1000, text: 'running' }, // the same value again: one segment
      { t_ms: 1500, text: 'idle' }, // same time as 'alarm' (listed first): 'alarm' has zero width and goes
      { t_ms: 2500, text: 'late' }, // after the window
    ] };
    const segs = laneSegments(lane, 250, 2000);
    expect(segs.map((s) => [s.text, s.from_ms, s.to_ms])).toEqual([
      ['manual', 250, 500],
      ['running', 500, 1500],
      ['idle', 1500, 2000],
    ]);
    expect(segs[0].left).toBe(0);
    expect(segs[1].left).toBeCloseTo((250 / 1750) * 100, 9);
    expect(segs[1].width).toBeCloseTo((1000 / 1750) * 100, 9);
    expect(segs[2].left + segs[2].width).toBeCloseTo(100, 9);
    // No window, no segments.
    expect(laneSegments(lane, 2000, 2000)).toEqual([]);
    expect(laneSegments(/** @type {any} */ ({ id: 'x' }), 0, 10)).toEqual([]);
    expect(hasWindow(DETAIL)).toBe(true);
    expect(hasWindow({ start_ms: 5, end_ms: 5 })).toBe(false);
    expect(hasWindow(null)).toBe(false);
  });

  it('positions and label alignment', () => {
    expect(percentAt(AT, DETAIL.start_ms, DETAIL.end_ms)).toBeCloseTo((120 / 130) * 100, 9);
    expect(percentAt(AT + 60000, DETAIL.start_ms, DETAIL.end_ms)).toBe(100);
    expect(percentAt(0, DETAIL.start_ms, DETAIL.end_ms)).toBe(0);
    expect(labelAlign(0)).toBe('start');
    expect(labelAlign(50)).toBe('middle');
    expect(labelAlign(100)).toBe('end');
  });

  it('axis ticks: 0 at the alarm, the ends, round steps; labels that would overlap are left out', () => {
    /** @param {import('../../../src/lib/features/recorder/logic.js').Tick[]} ticks @param {number} w */
    const noOverlap = (ticks, w) => {
      const ext = ticks.map((t) => labelExtent(t.left, t.label, t.align, w));
      for (let i = 1; i < ext.length; i++) expect(ext[i][0]).toBeGreaterThanOrEqual(ext[i - 1][1]);
    };
    // Desktop (a 1000 px axis): -120 s .. +10 s in 30 s steps, and the end.
    const wide = axisTicks(DETAIL.start_ms, DETAIL.end_ms, AT, 1000);
    expect(wide.map((t) => t.label)).toEqual([`${M}120 s`, `${M}90 s`, `${M}60 s`, `${M}30 s`, '0', '+10 s']);
    expect(wide[0]).toMatchObject({ left: 0, align: 'start', rel_ms: -120000 });
    expect(wide[4]).toMatchObject({ align: 'middle', rel_ms: 0 });
    expect(wide[5]).toMatchObject({ left: 100, align: 'end' });
    noOverlap(wide, 1000);
    // Phone (320 px): "+10 s" would overlap "0", "−90 s" the start's label.
    const narrow = axisTicks(DETAIL.start_ms, DETAIL.end_ms, AT, 320);
    expect(narrow.map((t) => t.label)).toEqual([`${M}120 s`, `${M}60 s`, `${M}30 s`, '0']);
    noOverlap(narrow, 320);
    for (const w of [120, 200, 260, 390, 600, 800, 1400]) {
      const t = axisTicks(DETAIL.start_ms, DETAIL.end_ms, AT, w);
      expect(t.map((x) => x.label)).toContain('0');
      noOverlap(t, w);
    }
    // A short recording gets finer steps (2 s here), the ends included.
    expect(axisTicks(AT - 5000, AT + 2000, AT, 800).map((t) => t.label)).toEqual([`${M}5 s`, `${M}4 s`, `${M}2 s`, '0', '+2 s']);
    // The alarm outside the window (an unknown recording's mtime): still relative to it, no 0.
    const outside = axisTicks(AT - 130000, AT - 10000, AT, 600);
    expect(outside.some((t) => t.label === '0')).toBe(false);
    expect(outside[0].label).toBe(`${M}130 s`);
    expect(outside.at(-1)?.label).toBe(`${M}10 s`);
    expect(axisTicks(5, 5, 5)).toEqual([]);
  });

  it('events: every change by time, lanes in order at the same time, with relative time and lane title', () => {
    const ev = timelineEvents(DETAIL);
    expect(ev.map((e) => [e.rel, e.lane, e.laneTitle, e.label])).toEqual([
      [`${M}120 s`, 'alarms', 'Alarms', 'No active alarm'],
      [`${M}120 s`, 'process', 'Process', 'running · Move to part 2 (approach)'],
      [`${M}120 s`, 'mode', 'Operation mode', 'running'],
      [`${M}3.2 s`, 'process', 'Process', 'error · Move failed: protective stop'],
      [`${M}0.1 s`, 'alarms', 'Alarms', 'robot.protective_stop: Robot protective stop'],
      [`${M}0.1 s`, 'mode', 'Operation mode', 'alarm'],
    ]);
    expect(ev[4].tone).toBe('danger');
    expect(ev[0]).toMatchObject({ text: '', tone: 'none' });
    expect(eventLabel('process', '')).toBe('No value');
    expect(timelineEvents(/** @type {any} */ ({ at_ms: 0 }))).toEqual([]);
  });

  it('the figure summary and the topics', () => {
    expect(timelineSummary(DETAIL)).toBe(
      `Alarm at ${formatDate(AT)}. From ${M}120 s to +10 s. Alarms: 2 changes, Process: 2 changes, Operation mode: 2 changes. The list of events below has every change.`,
    );
    expect(timelineSummary({ ...DETAIL, reason: 'saved by hand', alarms: [], timeline: { lanes: [] } })).toBe(
      `Saved at ${formatDate(AT)}. From ${M}120 s to +10 s. The list of events below has every change.`,
    );
    expect(topicRows(DETAIL.topics).map((t) => t.topic)).toEqual(['/joint_states', '/cell/alarms/list', '/cell/mode']);
    expect(topicRows(undefined)).toEqual([]);
  });
});
