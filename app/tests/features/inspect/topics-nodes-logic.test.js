// @vitest-environment node
// The Topics and Nodes views' plain logic: names, tabs, the graph's shape, filters, the measured figures' texts, the
// last message as a tree.
import { describe, it, expect } from 'vitest';
import {
  NAMES, TABS, tabId, tabAfterKey, GRAPH_POLL_MS, STATS_POLL_MS, ECHO_POLL_MS, normaliseGraph, filterTopics, filterNodes,
  pubSubText, countText, nodeCountText, aliveText, normaliseStats, formatRate, formatBytes, formatBandwidth, rateText,
  bandwidthText, meanSizeText, ageText, windowText, parseEcho, jsonKind, jsonChildren, cutArray, jsonSummary,
  jsonScalarText, notLiveView, normaliseEcho,
} from '../../../src/lib/features/inspect/logic.js';

/** @param {string} name @param {any} [o] */
const topic = (name, o = {}) => ({ name, type: 'std_msgs/String', publishers: [], subscribers: [], ...o });
/** @param {string} name @param {any} [o] */
const node = (name, o = {}) => ({ name, alive: true, module: '', publications: [], subscriptions: [], services: [], ...o });
/** @param {any} o a TopicStats answer */
const stats = (o) => normaliseStats({ ok: true, message: '', type: 'sensor_msgs/JointState', messages: 0, window_s: 1, rate_hz: 0, bandwidth_bps: 0, mean_bytes: 0, last_age_s: -1, ...o });

describe('names and polling periods', () => {
  it('calls the three inspect services by their names and types', () => {
    expect(NAMES.graph).toEqual({ service: '/cell/inspect/graph', type: 'cell_msgs/GetRosGraph' });
    expect(NAMES.topicStats).toEqual({ service: '/cell/inspect/topic_stats', type: 'cell_msgs/TopicStats' });
    expect(NAMES.echo).toEqual({ service: '/cell/inspect/echo', type: 'cell_msgs/TopicEcho' });
  });
  it('asks the figures often enough that the robot PC keeps measuring (it stops 10 s after the last ask)', () => {
    expect(STATS_POLL_MS).toBe(1000);
    expect(ECHO_POLL_MS).toBe(2000);
    expect(GRAPH_POLL_MS).toBe(5000);
  });
});

describe('tabs', () => {
  it('has Log, Topics, Nodes in that order; unknown ids fall back to the log', () => {
    expect(TABS.map((t) => [t.id, t.label])).toEqual([['log', 'Log'], ['topics', 'Topics'], ['nodes', 'Nodes'], ['diagnostics', 'Diagnostics']]);
    expect(tabId('nodes')).toBe('nodes');
    expect(tabId('diagnostics')).toBe('diagnostics');
    expect(tabId('graph')).toBe('log');
    expect(tabId(undefined)).toBe('log');
  });
  it('arrows wrap, Home and End jump, other keys do nothing', () => {
    expect(tabAfterKey('log', 'ArrowRight')).toBe('topics');
    expect(tabAfterKey('nodes', 'ArrowRight')).toBe('diagnostics');
    expect(tabAfterKey('diagnostics', 'ArrowRight')).toBe('log');
    expect(tabAfterKey('log', 'ArrowLeft')).toBe('diagnostics');
    expect(tabAfterKey('topics', 'ArrowLeft')).toBe('log');
    expect(tabAfterKey('topics', 'Home')).toBe('log');
    expect(tabAfterKey('log', 'End')).toBe('diagnostics');
    expect(tabAfterKey('log', 'Enter')).toBeNull();
    expect(tabAfterKey('log', 'a')).toBeNull();
  });
});

describe('the graph', () => {
  it('fills missing fields, drops unnamed entries, sorts by name', () => {
    const g = normaliseGraph({
      topics: [
        { name: '/z', type: 'std_msgs/Bool', publishers: ['/a', 3, null], subscribers: null },
        { name: '', type: 'x' },
        { name: '/a' },
      ],
      nodes: [{ name: '/n2', alive: 'yes', module: null }, { name: '/n1', alive: true, module: 'gripper', services: ['/n1/get_loggers'] }, null],
    });
    expect(g.topics).toEqual([
      { name: '/a', type: '', publishers: [], subscribers: [] },
      { name: '/z', type: 'std_msgs/Bool', publishers: ['/a'], subscribers: [] },
    ]);
    expect(g.nodes).toEqual([
      { name: '/n1', alive: true, module: 'gripper', publications: [], subscriptions: [], services: ['/n1/get_loggers'] },
      // Only a real `true` is alive: anything else reads "not responding".
      { name: '/n2', alive: false, module: '', publications: [], subscriptions: [], services: [] },
    ]);
    expect(normaliseGraph(null)).toEqual({ topics: [], nodes: [] });
    expect(normaliseGraph({ topics: 'nope' })).toEqual({ topics: [], nodes: [] });
  });

  it('filters topics by name or type, any case, every word', () => {
    const ts = [
      topic('/joint_states', { type: 'sensor_msgs/JointState' }),
      topic('/camera/image_raw', { type: 'sensor_msgs/Image' }),
      topic('/rosout', { type: 'rosgraph_msgs/Log' }),
    ];
    expect(filterTopics(ts, '')).toBe(ts);
    expect(filterTopics(ts, '   ')).toBe(ts);
    expect(filterTopics(ts, 'JOINT').map((t) => t.name)).toEqual(['/joint_states']);
    expect(filterTopics(ts, 'sensor_msgs').map((t) => t.name)).toEqual(['/joint_states', '/camera/image_raw']);
    expect(filterTopics(ts, 'sensor image').map((t) => t.name)).toEqual(['/camera/image_raw']);
    expect(filterTopics(ts, 'log').map((t) => t.name)).toEqual(['/rosout']);
    expect(filterTopics(ts, 'camera log')).toEqual([]);
  });

  it('filters nodes by name or module, any case, every word', () => {
    const ns = [node('/ur_driver', { module: 'robot' }), node('/gripper_node', { module: 'gripper' }), node('/rosout')];
    expect(filterNodes(ns, '')).toBe(ns);
    expect(filterNodes(ns, 'ROBOT').map((n) => n.name)).toEqual(['/ur_driver']);
    expect(filterNodes(ns, 'grip node').map((n) => n.name)).toEqual(['/gripper_node']);
    expect(filterNodes(ns, 'rosout').map((n) => n.name)).toEqual(['/rosout']);
    expect(filterNodes(ns, 'driver gripper')).toEqual([]);
  });

  it('counts: pub/sub, shown of total, nodes not responding', () => {
    expect(pubSubText(topic('/t', { publishers: ['/a', '/b'], subscribers: ['/c'] }))).toBe('2 pub · 1 sub');
    expect(countText(12, 12, 'topic')).toBe('12 topics');
    expect(countText(1, 1, 'topic')).toBe('1 topic');
    expect(countText(3, 12, 'topic')).toBe('3 of 12 topics');
    expect(countText(0, 0, 'node')).toBe('0 nodes');
    const all = [node('/a'), node('/b', { alive: false }), node('/c', { alive: false })];
    expect(nodeCountText(all, all)).toBe('3 nodes · 2 not responding');
    expect(nodeCountText([all[0]], all)).toBe('1 of 3 nodes · 2 not responding');
    expect(nodeCountText([all[0]], [all[0]])).toBe('1 node');
    expect(aliveText(all[0])).toBe('alive');
    expect(aliveText(all[1])).toBe('not responding');
  });

  it('says why the graph is not live', () => {
    expect(notLiveView('disconnected', 'graph')).toEqual({
      title: 'ROS disconnected', text: expect.stringContaining('topics and nodes shown may be out of date'),
    });
    expect(notLiveView('offline', 'graph')?.title).toBe('Offline');
    expect(notLiveView(null, 'graph')).toBeNull();
    // The log's own sentence is unchanged.
    expect(notLiveView('disconnected')?.text).toContain('the log is not live');
  });
});

describe('measured figures', () => {
  it('formats a rate to about four figures', () => {
    expect(formatRate(124.8)).toBe('124.8 Hz');
    expect(formatRate(124.849)).toBe('124.8 Hz');
    expect(formatRate(50)).toBe('50.0 Hz');
    expect(formatRate(9.98)).toBe('9.98 Hz');
    expect(formatRate(1)).toBe('1.00 Hz');
    expect(formatRate(0.5)).toBe('0.500 Hz');
    expect(formatRate(1500.4)).toBe('1500 Hz');
    expect(formatRate(-1)).toBe('—');
    expect(formatRate(NaN)).toBe('—');
  });

  it('formats sizes and bandwidth in decimal units (as rostopic bw)', () => {
    expect(formatBytes(0)).toBe('0 B');
    expect(formatBytes(850)).toBe('850 B');
    expect(formatBytes(999.4)).toBe('999 B');
    expect(formatBytes(999.6)).toBe('1.0 KB');
    expect(formatBytes(12300)).toBe('12.3 KB');
    expect(formatBytes(123456)).toBe('123 KB');
    expect(formatBytes(1_500_000)).toBe('1.5 MB');
    expect(formatBytes(27_648_000)).toBe('27.6 MB');
    expect(formatBytes(2e9)).toBe('2.0 GB');
    expect(formatBytes(-5)).toBe('—');
    expect(formatBandwidth(12345)).toBe('12.3 KB/s');
    expect(formatBandwidth(120)).toBe('120 B/s');
    expect(formatBandwidth(Infinity)).toBe('—');
  });

  it('reads a service answer with every figure a number; -1 age when none', () => {
    expect(normaliseStats({ ok: true, messages: '12', rate_hz: 10.5, last_age_s: null })).toEqual({
      ok: true, message: '', type: '', messages: 12, window_s: 0, rate_hz: 10.5, bandwidth_bps: 0, mean_bytes: 0, last_age_s: -1,
    });
    expect(normaliseStats(undefined).ok).toBe(false);
    expect(normaliseStats({ ok: 1 }).ok).toBe(false);
  });

  it('rate: measuring until two messages, then the rate; no messages after 3 s; slow topics once the window is full', () => {
    expect(rateText(null, 0)).toBe('measuring…');
    expect(rateText(stats({ messages: 0, last_age_s: -1 }), 1)).toBe('measuring…');
    expect(rateText(stats({ messages: 0, last_age_s: -1, window_s: 1 }), 2.9)).toBe('measuring…');
    expect(rateText(stats({ messages: 0, last_age_s: -1, window_s: 1 }), 3)).toBe('no messages');
    // Another page started measuring earlier: the robot PC has been listening for 10 s already.
    expect(rateText(stats({ messages: 0, last_age_s: -1, window_s: 10 }), 0)).toBe('no messages');
    expect(rateText(stats({ messages: 1, last_age_s: 0.1, window_s: 2 }), 2)).toBe('measuring…');
    expect(rateText(stats({ messages: 2, rate_hz: 124.8, last_age_s: 0.01 }), 0.5)).toBe('124.8 Hz');
    expect(rateText(stats({ messages: 1, last_age_s: 4, window_s: 10 }), 12)).toBe('1 message in the last 10 s');
    expect(rateText(stats({ messages: 0, last_age_s: 25, window_s: 10 }), 30)).toBe('no messages in the last 10 s');
    expect(rateText(stats({ ok: false, message: 'no such topic' }), 10)).toBe('—');
  });

  it('bandwidth, mean size, last message age, window', () => {
    expect(bandwidthText(null, 0)).toBe('measuring…');
    expect(bandwidthText(stats({ messages: 5, bandwidth_bps: 12345 }), 1)).toBe('12.3 KB/s');
    expect(bandwidthText(stats({ messages: 0, last_age_s: -1, window_s: 1 }), 1)).toBe('measuring…');
    expect(bandwidthText(stats({ messages: 0, last_age_s: -1, window_s: 1 }), 4)).toBe('no messages');
    expect(bandwidthText(stats({ messages: 0, last_age_s: 20, window_s: 10 }), 4)).toBe('0 B/s');
    expect(meanSizeText(stats({ messages: 3, mean_bytes: 921654 }))).toBe('922 KB');
    expect(meanSizeText(stats({ messages: 0 }))).toBe('—');
    expect(meanSizeText(null)).toBe('—');
    expect(ageText(-1)).toBe('none received yet');
    expect(ageText(0.0349)).toBe('35 ms ago');
    expect(ageText(2.54)).toBe('2.5 s ago');
    expect(ageText(185)).toBe('3 min ago');
    expect(ageText(7300)).toBe('2 h ago');
    expect(windowText(stats({ window_s: 9.6 }))).toBe('Over the last 10 s');
    expect(windowText(stats({ ok: false }))).toBe('');
  });
});

describe('the last message', () => {
  it('parses JSON; anything else is kept raw with the reason', () => {
    expect(parseEcho('{"a": [1, 2]}')).toEqual({ parsed: true, value: { a: [1, 2] } });
    expect(parseEcho('null')).toEqual({ parsed: true, value: null });
    const bad = parseEcho('{"a": nan}');
    expect(bad.parsed).toBe(false);
    expect(bad).toMatchObject({ raw: '{"a": nan}' });
    expect(parseEcho('')).toEqual({ parsed: false, raw: '', error: 'empty' });
    expect(parseEcho(undefined)).toMatchObject({ parsed: false, raw: '' });
  });

  it('reads the echo answer: fields of their types, -1 age when none', () => {
    expect(normaliseEcho({ ok: true, type: 'std_msgs/String', json: '{"data": "hi"}', age_s: 0.25 }))
      .toEqual({ ok: true, message: '', type: 'std_msgs/String', json: '{"data": "hi"}', age_s: 0.25 });
    expect(normaliseEcho({ ok: false, message: 'nothing received yet', age_s: null })).toEqual({ ok: false, message: 'nothing received yet', type: '', json: '', age_s: -1 });
    expect(normaliseEcho(undefined).ok).toBe(false);
  });

  it('describes branches and leaves as JSON writes them', () => {
    expect([{}, [], 'x', 1, true, null, undefined].map(jsonKind)).toEqual(['object', 'array', 'string', 'number', 'boolean', 'null', 'null']);
    expect(jsonChildren({ b: 1, a: { c: 2 } })).toEqual([{ key: 'b', value: 1 }, { key: 'a', value: { c: 2 } }]);
    expect(jsonChildren(['x', 'y'])).toEqual([{ key: '0', value: 'x' }, { key: '1', value: 'y' }]);
    expect(jsonChildren(3)).toEqual([]);
    expect(jsonSummary({ a: 1, b: 2 })).toBe('{2 fields}');
    expect(jsonSummary({ a: 1 })).toBe('{1 field}');
    expect(jsonSummary([1, 2, 3])).toBe('[3 items]');
    expect(jsonSummary([])).toBe('[0 items]');
    expect(jsonScalarText('say "hi"')).toBe('"say \\"hi\\""');
    expect(jsonScalarText('<921600 bytes>')).toBe('"<921600 bytes>"');
    expect(jsonScalarText(null)).toBe('null');
    expect(jsonScalarText(1.5)).toBe('1.5');
    expect(jsonScalarText(false)).toBe('false');
  });

  it('recognises an array the robot PC cut', () => {
    expect(cutArray([1, 2, 3, '… 97 more (100 items)'])).toEqual({ total: 100, shown: 3 });
    expect(cutArray([1, 2, '... 5 more (7 items)'])).toEqual({ total: 7, shown: 2 });
    expect(cutArray([1, 2, 3])).toBeNull();
    expect(cutArray(['97 more'])).toBeNull();
    expect(jsonSummary([0.1, 0.2, '… 97 more (100 items)'])).toBe('[100 items, first 2 shown]');
  });
});
