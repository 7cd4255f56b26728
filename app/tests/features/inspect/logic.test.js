// @vitest-environment node
import { describe, it, expect } from 'vitest';
import {
  NAMES, HISTORY_REQUEST, KEEP_ENTRIES, LIVE_QUEUE_LENGTH, LEVELS, levelName, levelView, rosTimeUs, normaliseEntry,
  mergeEntries, filterEntries, NO_FILTERS, isFiltered, newestFirst, nodeList, formatClock, isoTime, sourceText,
  spanText, keepText, historyText, shownText, newEntriesText, notLiveView, exportLine, exportText, exportFileName,
} from '../../../src/lib/features/inspect/logic.js';

const SECS = 1795010712; // November 2026
/** @param {number} secs @param {number} nsecs @param {any} [o] a RosLogEntry (the service's shape) */
const svc = (secs, nsecs, o = {}) => ({
  stamp: { secs, nsecs }, level: 2, node: '/process_node', msg: 'Move to part 2', file: 'process.py', function: 'run', line: 120, ...o,
});
/** @param {number} secs @param {number} nsecs @param {any} [o] a rosgraph_msgs/Log (the topic's shape) */
const topic = (secs, nsecs, o = {}) => ({
  header: { seq: 1, stamp: { secs, nsecs }, frame_id: '' }, level: 2, name: '/process_node', msg: 'Move to part 2',
  file: 'process.py', function: 'run', line: 120, topics: ['/rosout'], ...o,
});
/** @param {number} i  an entry i ms after SECS, from the topic @param {any} [o] */
const live = (i, o = {}) => normaliseEntry(topic(SECS, i * 1e6, { msg: `entry ${i}`, ...o }));

describe('names and the history request', () => {
  it('asks for everything, the newest 2000, and subscribes with a bounded queue', () => {
    expect(NAMES.log).toEqual({ service: '/cell/inspect/log', type: 'cell_msgs/LogQuery' });
    expect(NAMES.rosout).toEqual({ topic: '/rosout_agg', type: 'rosgraph_msgs/Log' });
    expect(HISTORY_REQUEST).toEqual({ min_level: 0, node: '', text: '', max_entries: 2000 });
    expect(KEEP_ENTRIES).toBe(2000);
    expect(LIVE_QUEUE_LENGTH).toBeGreaterThan(1);
    expect(LIVE_QUEUE_LENGTH).toBeLessThanOrEqual(100);
  });
});

describe('levels', () => {
  it('maps rosgraph_msgs/Log numbers to names, labels and tones', () => {
    expect([1, 2, 4, 8, 16].map(levelName)).toEqual(['debug', 'info', 'warn', 'error', 'fatal']);
    expect(LEVELS.map((l) => [l.name, l.value, l.upper, l.tone])).toEqual([
      ['debug', 1, 'DEBUG', 'neutral'], ['info', 2, 'INFO', 'info'], ['warn', 4, 'WARN', 'warn'],
      ['error', 8, 'ERROR', 'danger'], ['fatal', 16, 'FATAL', 'fatal'],
    ]);
    expect(levelView('warn')).toMatchObject({ value: 4, label: 'Warn', upper: 'WARN' });
    expect(levelView(8).name).toBe('error');
  });
  it('a number between levels counts as the lower one; junk as debug; names too', () => {
    expect([0, 3, 5, 12, 32, -1, NaN, undefined, null].map(levelName)).toEqual(['debug', 'info', 'warn', 'error', 'fatal', 'debug', 'debug', 'debug', 'debug']);
    expect(['WARN', 'warning', 'Error', '8', 'loud'].map(levelName)).toEqual(['warn', 'warn', 'error', 'error', 'info']);
  });
});

describe('normaliseEntry', () => {
  it('makes one shape from the service\'s RosLogEntry and the topic\'s rosgraph_msgs/Log', () => {
    const a = normaliseEntry(svc(SECS, 123456789, { level: 4 }));
    const b = normaliseEntry(topic(SECS, 123456789, { level: 4 }));
    expect(a).toEqual({
      t_ms: (SECS * 1e6 + 123457) / 1000, level: 4, levelName: 'warn', node: '/process_node', msg: 'Move to part 2',
      file: 'process.py', function: 'run', line: 120, key: `${SECS}123457|/process_node|120|Move to part 2`,
    });
    expect(b).toEqual(a);
  });
  it('accepts {sec, nanosec}; an entry without a stamp gets the fallback time; missing fields are empty', () => {
    expect(normaliseEntry({ stamp: { sec: 10, nanosec: 5e8 }, level: 2, node: 'n', msg: 'm' }).t_ms).toBe(10500);
    const e = normaliseEntry({ header: { stamp: { secs: 0, nsecs: 0 } }, level: 8 }, 1234.5);
    expect(e).toMatchObject({ t_ms: 1234.5, levelName: 'error', node: '', msg: '', file: '', function: '', line: 0 });
    expect(normaliseEntry(null, 7).t_ms).toBe(7);
  });
  it('the key holds only the start of a very long message (the robot PC cuts those)', () => {
    const long = 'x'.repeat(5000);
    const a = normaliseEntry(topic(SECS, 0, { msg: long }));
    const b = normaliseEntry(svc(SECS, 0, { msg: `${long.slice(0, 4000)} [cut]` }));
    expect(a.key).toBe(b.key);
    expect(a.key.length).toBeLessThan(300);
  });
  it('rosTimeUs rounds to the µs and is null for unset times', () => {
    expect(rosTimeUs({ secs: 1, nsecs: 1499 })).toBe(1000001);
    expect(rosTimeUs({ secs: 0, nsecs: 0 })).toBeNull();
    expect(rosTimeUs(undefined)).toBeNull();
  });
});

describe('mergeEntries', () => {
  it('history plus live: each entry once, oldest first; the live entries that came during the call are kept', () => {
    const history = [0, 1, 2, 3].map((i) => normaliseEntry(svc(SECS, i * 1e6, { msg: `entry ${i}` })));
    // Arrived (and were applied) while the history call was in flight: 2 and 3 overlap, 4 and 5 are newer.
    let kept = mergeEntries([], [2, 3, 4, 5].map((i) => live(i))).entries;
    const r = mergeEntries(kept, history);
    expect(r.added).toBe(2);
    expect(r.entries.map((e) => e.msg)).toEqual(['entry 0', 'entry 1', 'entry 2', 'entry 3', 'entry 4', 'entry 5']);
    // Again after a reconnect: nothing new.
    const again = mergeEntries(r.entries, history);
    expect(again.added).toBe(0);
    expect(again.entries).toBe(r.entries);
  });
  it('the stamp the history went through (float seconds) still matches the live one', () => {
    // rospy: Time.from_sec(stamp.to_sec()) truncates: the nanoseconds move by up to ~250 ns.
    const exact = live(0, { header: { stamp: { secs: SECS, nsecs: 500 } } }); // 0.5 µs: rounds up
    const viaFloat = normaliseEntry(svc(SECS, 300, { msg: 'entry 0' })); // 0.3 µs: rounds down
    expect(viaFloat.key).not.toBe(exact.key);
    expect(mergeEntries([exact], [viaFloat]).added).toBe(0);
    expect(mergeEntries([viaFloat], [exact]).added).toBe(0);
  });
  it('the same message from the same line at another time is another entry; so is another node, line or message', () => {
    const a = live(0, { msg: 'tick' });
    const b = live(1, { msg: 'tick' });
    const c = live(0, { msg: 'tick', name: '/other' });
    const d = live(0, { msg: 'tick', line: 7 });
    const e = live(0, { msg: 'tock' });
    const f = normaliseEntry(topic(SECS, 2000, { msg: 'tick' })); // 2 µs later
    const r = mergeEntries([a], [b, c, d, e, f, a]);
    expect(r.added).toBe(5);
    expect(new Set(r.entries.map((x) => x.key)).size).toBe(6);
  });
  it('duplicates inside one batch count once', () => {
    const r = mergeEntries([], [live(1), live(1), live(2)]);
    expect(r.entries.map((e) => e.msg)).toEqual(['entry 1', 'entry 2']);
  });
  it('sorts by time, stable for equal stamps, and keeps the newest max', () => {
    const same1 = live(5, { msg: 'first' });
    const same2 = live(5, { msg: 'second' });
    const r = mergeEntries([live(1), live(9)], [same1, live(3), same2, live(0)], 4);
    expect(r.entries.map((e) => e.msg)).toEqual(['entry 3', 'first', 'second', 'entry 9']);
    expect(r.added).toBe(4);
  });
  it('keeps at most 2000 by default (a storm pushes the oldest out)', () => {
    let kept = /** @type {ReturnType<typeof live>[]} */ ([]);
    for (let b = 0; b < 5; b++) kept = mergeEntries(kept, Array.from({ length: 1000 }, (_, i) => live(b * 1000 + i))).entries;
    expect(kept.length).toBe(2000);
    expect(kept[0].msg).toBe('entry 3000');
    expect(kept.at(-1)?.msg).toBe('entry 4999');
  });
});

describe('filters', () => {
  const entries = [
    live(0, { level: 1, name: '/driver', msg: 'rtde tick', file: 'driver.cpp' }),
    live(1, { level: 2, name: '/process_node', msg: 'Move to part 2', file: 'process.py' }),
    live(2, { level: 4, name: '/process_node', msg: 'Slow cycle', file: 'process.py' }),
    live(3, { level: 8, name: '/driver', msg: 'Protective stop', file: 'ur_driver.cpp' }),
    live(4, { level: 16, name: '/gripper', msg: 'Lost the gripper', file: 'gripper.py' }),
  ];
  const f = (/** @type {any} */ o) => filterEntries(entries, { ...NO_FILTERS, ...o }).map((e) => e.msg);

  it('no filters: the same list', () => {
    expect(filterEntries(entries, NO_FILTERS)).toBe(entries);
    expect(isFiltered(NO_FILTERS)).toBe(false);
    expect(isFiltered({ ...NO_FILTERS, minLevel: 'info' })).toBe(true);
    expect(isFiltered({ ...NO_FILTERS, text: '  ' })).toBe(false);
  });
  it('minimum level: that level and above', () => {
    expect(f({ minLevel: 'warn' })).toEqual(['Slow cycle', 'Protective stop', 'Lost the gripper']);
    expect(f({ minLevel: 'fatal' })).toEqual(['Lost the gripper']);
  });
  it('node: exactly that node', () => {
    expect(f({ node: '/driver' })).toEqual(['rtde tick', 'Protective stop']);
  });
  it('text: in the message, node or file, any case, trimmed', () => {
    expect(f({ text: 'STOP' })).toEqual(['Protective stop']);
    expect(f({ text: 'gripp ' })).toEqual(['Lost the gripper']);
    expect(f({ text: 'ur_driver' })).toEqual(['Protective stop']);
    expect(f({ text: 'process_node' })).toEqual(['Move to part 2', 'Slow cycle']);
  });
  it('all together', () => {
    expect(f({ minLevel: 'warn', node: '/driver', text: 'stop' })).toEqual(['Protective stop']);
    expect(f({ minLevel: 'error', node: '/process_node' })).toEqual([]);
  });
  it('newest first, at most max', () => {
    expect(newestFirst(entries, 2).map((e) => e.msg)).toEqual(['Lost the gripper', 'Protective stop']);
    expect(newestFirst(entries).length).toBe(5);
  });
  it('the node list: sorted, each once, the picked one kept', () => {
    expect(nodeList(entries)).toEqual(['/driver', '/gripper', '/process_node']);
    expect(nodeList([...entries, live(5, { name: '' })], '/gone')).toEqual(['/driver', '/gone', '/gripper', '/process_node']);
  });
});

describe('texts', () => {
  it('formatClock: local HH:MM:SS.mmm', () => {
    const t = new Date(2026, 10, 26, 9, 5, 3, 7).getTime() + 0.9;
    expect(formatClock(t)).toBe('09:05:03.007');
    expect(formatClock(NaN)).toBe('--:--:--.---');
  });
  it('sourceText: file:line, the file alone without a line, nothing without a file', () => {
    const e = live(0);
    expect(sourceText(e)).toBe('process.py:120');
    expect(sourceText({ ...e, line: 0 })).toBe('process.py');
    expect(sourceText({ ...e, file: '' })).toBe('');
  });
  it('spans, what the robot PC keeps', () => {
    expect([0, 44.6, 59.4, 60, 600, 7200, 7500].map(spanText)).toEqual(['0 s', '45 s', '59 s', '1 min', '10 min', '2 h', '2 h 5 min']);
    expect(keepText({ log_keep_entries: 5000, log_keep_s: 600 })).toBe('The robot PC keeps the last 10 min of the ROS log, at most 5000 entries; this page keeps the newest 2000.');
    expect(keepText(undefined)).toBe(keepText({ log_keep_entries: 5000, log_keep_s: 600 }));
  });
  it('historyText from the service answer', () => {
    expect(historyText({ entries: new Array(2000).fill({}), matched: 5000, dropped: 12, kept_s: 598.2 }))
      .toBe('History: the last 10 min (5000 entries kept on the robot PC, 12 dropped) · the newest 2000 loaded');
    expect(historyText({ entries: new Array(40).fill({}), matched: 40, dropped: 0, kept_s: 30 }))
      .toBe('History: the last 30 s (40 entries kept on the robot PC, 0 dropped)');
    expect(historyText({ entries: [{}], matched: 1, dropped: 0, kept_s: 0 })).toBe('History: the last 0 s (1 entry kept on the robot PC, 0 dropped)');
    expect(historyText({ entries: [], matched: 0, dropped: 3, kept_s: 0 })).toBe('History: no entries kept on the robot PC yet (3 dropped)');
    expect(historyText(null)).toBe('');
  });
  it('shownText', () => {
    expect(shownText(300, 1234, 2000)).toBe('Showing the newest 300 of 1234 entries (filtered from 2000)');
    expect(shownText(300, 2000, 2000)).toBe('Showing the newest 300 of 2000 entries');
    expect(shownText(12, 12, 12)).toBe('12 entries');
    expect(shownText(1, 1, 5)).toBe('1 entry (filtered from 5)');
    expect(shownText(0, 0, 5)).toBe('No entries match the filters (5 entries kept)');
    expect(shownText(0, 0, 0)).toBe('');
  });
  it('new entries while paused; why not live', () => {
    expect(newEntriesText(12)).toBe('12 new entries');
    expect(newEntriesText(1)).toBe('1 new entry');
    expect(notLiveView('offline')?.title).toBe('Offline');
    expect(notLiveView('disconnected')?.title).toBe('ROS disconnected');
    expect(notLiveView(null)).toBeNull();
  });
});

describe('export', () => {
  const t = Date.UTC(2026, 10, 26, 14, 5, 12, 123);
  const e = normaliseEntry(topic(Math.floor(t / 1000), 123456789, { level: 4, msg: 'Slow cycle:\n3.2 s over' }));
  it('one line per entry: ISO time, level, node, message (newlines escaped), file:line', () => {
    expect(isoTime(e.t_ms)).toBe('2026-11-26T14:05:12.123Z');
    expect(exportLine(e)).toBe('2026-11-26T14:05:12.123Z WARN /process_node Slow cycle:\\n3.2 s over process.py:120');
    expect(exportLine({ ...e, file: '', node: '' })).toBe('2026-11-26T14:05:12.123Z WARN - Slow cycle:\\n3.2 s over');
  });
  it('the file: oldest first, a newline after each line; empty for no entries', () => {
    const f = normaliseEntry(topic(Math.floor(t / 1000) + 1, 0, { level: 16, msg: 'Lost', name: '/gripper', file: 'g.py', line: 3 }));
    expect(exportText([e, f])).toBe(`${exportLine(e)}\n2026-11-26T14:05:13.000Z FATAL /gripper Lost g.py:3\n`);
    expect(exportText([])).toBe('');
  });
  it('the file name carries the time of the export', () => {
    expect(exportFileName(t)).toBe('ros-log-20261126T140512Z.log');
  });
});
