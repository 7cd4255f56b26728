// The Inspect page's Topics and Nodes views against a fake rosbridge (tests/fakeRos.js), on fake timers so the
// polling (graph every 5 s, figures every 1 s, last message every 2 s) can be stepped: the tabs, the topics list,
// a topic's measured figures (asked only while shown), its last message (only where can_echo), the nodes.
import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, fireEvent, within, cleanup } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import InspectPage from '../../../src/lib/features/inspect/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { makeFakeFactory } from '../../fakeRos.js';

const feature = { id: 'inspect', path: '/inspect', title: 'Inspect', icon: '', load: async () => ({ default: InspectPage }) };
const section = { log_keep_entries: 5000, log_keep_s: 600, can_echo: false };
const echoSection = { ...section, can_echo: true };

const GRAPH = {
  topics: [
    { name: '/camera/image_raw', type: 'sensor_msgs/Image', publishers: ['/camera_node'], subscribers: [] },
    { name: '/joint_states', type: 'sensor_msgs/JointState', publishers: ['/ur_driver'], subscribers: ['/robot_state_publisher', '/cell_relay'] },
    { name: '/rosout', type: 'rosgraph_msgs/Log', publishers: ['/ur_driver', '/camera_node'], subscribers: ['/rosout'] },
  ],
  nodes: [
    { name: '/camera_node', alive: false, module: 'camera', publications: ['/camera/image_raw', '/rosout'], subscriptions: [], services: ['/camera_node/get_loggers'] },
    { name: '/rosout', alive: true, module: '', publications: ['/rosout_agg'], subscriptions: ['/rosout'], services: [] },
    { name: '/ur_driver', alive: true, module: 'robot', publications: ['/joint_states', '/rosout'], subscriptions: [], services: [] },
  ],
};
/** @param {any} [o] a TopicStats answer */
const STATS = (o = {}) => ({
  ok: true, message: '', type: 'sensor_msgs/JointState', messages: 1248, window_s: 10, rate_hz: 124.8, bandwidth_bps: 12345,
  mean_bytes: 98.9, last_age_s: 0.004, ...o,
});

/** @type {ReturnType<typeof makeFakeFactory>} */
let f;

beforeEach(() => {
  vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout', 'setInterval', 'clearInterval', 'Date'] });
  ros.stop();
  f = makeFakeFactory();
  ros.factory = f.factory;
  ros.url = () => 'ws://test/ros';
  session.offline = false;
  session.user = { username: 'admin', role: 'admin' };
  session.config = /** @type {any} */ ({ commands: [], features: { inspect: section } });
});
afterEach(() => {
  cleanup();
  ros.stop();
  vi.useRealTimers();
  vi.restoreAllMocks();
});

/** Let time pass (timers, then promise callbacks), then draw. @param {number} [ms] */
async function settle(ms = 0) {
  await vi.advanceTimersByTimeAsync(ms);
  flushSync();
}
async function connect() {
  ros.start();
  await settle();
  f.rosList.at(-1)?.emit('connection');
  flushSync();
  await settle();
}
/** @param {string} name */
const callsTo = (name) => f.calls.filter((c) => c.name === name);
const graphCalls = () => callsTo('/cell/inspect/graph');
const statsCalls = () => callsTo('/cell/inspect/topic_stats');
const echoCalls = () => callsTo('/cell/inspect/echo');
/** Answer the newest graph call. @param {any} [g] */
async function answerGraph(g = GRAPH) {
  graphCalls().at(-1)?.ok(g);
  await settle();
}
/** @param {string} name */
const tab = (name) => screen.getByRole('tab', { name });
/** @param {string} name */
async function showTab(name) {
  await fireEvent.click(tab(name));
  await settle();
}
/** @param {string} name */
async function openTopic(name) {
  await fireEvent.click(screen.getByRole('button', { name: `Topic ${name}` }));
  await settle();
}

describe('Inspect tabs', () => {
  it('shows the log first; Topics and Nodes switch views, and only the shown view runs', async () => {
    render(InspectPage, { feature, section });
    const list = screen.getByRole('tablist', { name: 'Inspect views' });
    expect(within(list).getAllByRole('tab').map((t) => t.textContent)).toEqual(['Log', 'Topics', 'Nodes', 'Diagnostics']);
    expect(tab('Log').getAttribute('aria-selected')).toBe('true');
    expect(tab('Topics').getAttribute('aria-selected')).toBe('false');
    expect(screen.getByRole('tabpanel').getAttribute('aria-labelledby')).toBe(tab('Log').id);
    await connect();
    expect(screen.getByTestId('inspect-log')).toBeTruthy();
    const live = f.topicsNamed('/rosout_agg').at(-1);
    expect(live?.unsubscribed).toBe(false);
    expect(graphCalls()).toHaveLength(0);

    await showTab('Topics');
    expect(tab('Topics').getAttribute('aria-selected')).toBe('true');
    expect(tab('Log').getAttribute('aria-selected')).toBe('false');
    expect(screen.getByRole('tabpanel').getAttribute('aria-labelledby')).toBe(tab('Topics').id);
    expect(screen.queryByTestId('inspect-log')).toBeNull();
    expect(screen.getByTestId('inspect-topics')).toBeTruthy();
    // The log's subscription ended with its view.
    expect(live?.unsubscribed).toBe(true);
    expect(graphCalls()).toHaveLength(1);
    expect(graphCalls()[0].type).toBe('cell_msgs/GetRosGraph');
    expect(graphCalls()[0].args).toEqual({});

    await showTab('Nodes');
    expect(screen.queryByTestId('inspect-topics')).toBeNull();
    expect(screen.getByTestId('inspect-nodes')).toBeTruthy();
    expect(graphCalls()).toHaveLength(2);

    // Back to the log: subscribed again, the history read again.
    await showTab('Log');
    expect(screen.getByTestId('inspect-log')).toBeTruthy();
    expect(f.topicsNamed('/rosout_agg').filter((t) => !t.unsubscribed)).toHaveLength(1);
    expect(callsTo('/cell/inspect/log')).toHaveLength(2);
  });

  it('arrow keys move along the tabs (one tab stop)', async () => {
    render(InspectPage, { feature, section });
    expect(tab('Log').tabIndex).toBe(0);
    expect(tab('Topics').tabIndex).toBe(-1);
    tab('Log').focus();
    await fireEvent.keyDown(tab('Log'), { key: 'ArrowRight' });
    expect(tab('Topics').getAttribute('aria-selected')).toBe('true');
    expect(document.activeElement).toBe(tab('Topics'));
    expect(tab('Topics').tabIndex).toBe(0);
    await fireEvent.keyDown(tab('Topics'), { key: 'End' });
    expect(tab('Diagnostics').getAttribute('aria-selected')).toBe('true');
    await fireEvent.keyDown(tab('Diagnostics'), { key: 'ArrowRight' });
    expect(tab('Log').getAttribute('aria-selected')).toBe('true');
  });
});

describe('Topics view', () => {
  it('lists the graph\'s topics with type and pub/sub counts; filters; reads the graph every 5 s and on Refresh', async () => {
    render(InspectPage, { feature, section });
    await showTab('Topics');
    expect(screen.getByTestId('topic-empty').textContent).toContain('Waiting for the connection to ROS');
    expect(/** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Refresh topics' })).disabled).toBe(true);
    await connect();
    expect(graphCalls()).toHaveLength(1);
    await answerGraph();

    const rows = screen.getAllByTestId('topic-row');
    expect(rows.map((r) => r.dataset.topic)).toEqual(['/camera/image_raw', '/joint_states', '/rosout']);
    expect(rows[1].textContent).toContain('/joint_states');
    expect(rows[1].textContent).toContain('sensor_msgs/JointState');
    expect(rows[1].textContent).toContain('1 pub · 2 sub');
    expect(within(rows[1]).getByRole('button').getAttribute('aria-label')).toBe('Topic /joint_states');
    expect(screen.getByTestId('topic-count').textContent).toBe('3 topics');

    await fireEvent.input(screen.getByRole('searchbox', { name: 'Filter topics' }), { target: { value: 'sensor_msgs' } });
    expect(screen.getAllByTestId('topic-row').map((r) => r.dataset.topic)).toEqual(['/camera/image_raw', '/joint_states']);
    expect(screen.getByTestId('topic-count').textContent).toBe('2 of 3 topics');
    await fireEvent.input(screen.getByRole('searchbox', { name: 'Filter topics' }), { target: { value: 'nothing' } });
    expect(screen.getByTestId('topic-empty').textContent).toBe('No topics match the filter.');
    await fireEvent.input(screen.getByRole('searchbox', { name: 'Filter topics' }), { target: { value: '' } });

    // Every 5 s after the last answer.
    await settle(4900);
    expect(graphCalls()).toHaveLength(1);
    await settle(100);
    expect(graphCalls()).toHaveLength(2);
    await answerGraph({ ...GRAPH, topics: GRAPH.topics.slice(1) });
    expect(screen.getAllByTestId('topic-row')).toHaveLength(2);

    await fireEvent.click(screen.getByRole('button', { name: 'Refresh topics' }));
    await settle();
    expect(graphCalls()).toHaveLength(3);
    await answerGraph();
    expect(screen.getAllByTestId('topic-row')).toHaveLength(3);
  });

  it('opening a topic asks for its figures every second and shows the rate; Close stops asking', async () => {
    render(InspectPage, { feature, section });
    await showTab('Topics');
    await connect();
    await answerGraph();
    await openTopic('/joint_states');

    const detail = screen.getByTestId('topic-detail');
    expect(within(detail).getByRole('heading', { name: '/joint_states' })).toBeTruthy();
    expect(within(detail).getByTestId('topic-type').textContent).toBe('sensor_msgs/JointState');
    expect(within(within(detail).getByRole('list', { name: 'Publishers of /joint_states' })).getAllByRole('listitem').map((li) => li.textContent)).toEqual(['/ur_driver']);
    expect(within(within(detail).getByRole('list', { name: 'Subscribers of /joint_states' })).getAllByRole('listitem').map((li) => li.textContent))
      .toEqual(['/robot_state_publisher', '/cell_relay']);
    const row = screen.getAllByTestId('topic-row').find((r) => r.dataset.topic === '/joint_states');
    expect(row?.querySelector('button')?.getAttribute('aria-current')).toBe('true');

    expect(statsCalls()).toHaveLength(1);
    expect(statsCalls()[0].type).toBe('cell_msgs/TopicStats');
    expect(statsCalls()[0].args).toEqual({ topic: '/joint_states' });
    expect(screen.getByTestId('topic-rate').textContent).toBe('measuring…');
    statsCalls()[0].ok(STATS({ messages: 1, window_s: 0.2, rate_hz: 0, last_age_s: 0.1 }));
    await settle();
    expect(screen.getByTestId('topic-rate').textContent).toBe('measuring…');

    await settle(1000);
    expect(statsCalls()).toHaveLength(2);
    statsCalls()[1].ok(STATS());
    await settle();
    expect(screen.getByTestId('topic-rate').textContent).toBe('124.8 Hz');
    expect(screen.getByTestId('topic-bandwidth').textContent).toBe('12.3 KB/s');
    expect(screen.getByTestId('topic-size').textContent).toBe('99 B');
    expect(screen.getByTestId('topic-last').textContent).toBe('4 ms ago');
    expect(screen.getByTestId('topic-window').textContent).toContain('Over the last 10 s');

    await settle(1000);
    expect(statsCalls()).toHaveLength(3);
    statsCalls()[2].ok(STATS({ rate_hz: 125.04 }));
    await settle();
    expect(screen.getByTestId('topic-rate').textContent).toBe('125.0 Hz');

    await fireEvent.click(screen.getByRole('button', { name: 'Close topic details' }));
    await settle();
    expect(screen.queryByTestId('topic-detail')).toBeNull();
    await settle(15000);
    expect(statsCalls()).toHaveLength(3);
  });

  it('choosing another topic, or another tab, stops asking for the first', async () => {
    render(InspectPage, { feature, section });
    await showTab('Topics');
    await connect();
    await answerGraph();
    await openTopic('/joint_states');
    statsCalls()[0].ok(STATS());
    await settle(1000);
    expect(statsCalls().map((c) => c.args.topic)).toEqual(['/joint_states', '/joint_states']);

    await openTopic('/rosout');
    expect(screen.getByTestId('topic-detail').dataset.topic).toBe('/rosout');
    // The unanswered call for the first topic is dropped when it comes.
    statsCalls()[1].ok(STATS({ rate_hz: 999 }));
    statsCalls()[2].ok(STATS({ rate_hz: 3.5, type: 'rosgraph_msgs/Log' }));
    await settle();
    expect(screen.getByTestId('topic-rate').textContent).toBe('3.50 Hz');
    await settle(3000);
    expect(statsCalls().slice(2).every((c) => c.args.topic === '/rosout')).toBe(true);
    expect(statsCalls()).toHaveLength(4);

    await showTab('Nodes');
    const n = statsCalls().length;
    await settle(15000);
    expect(statsCalls()).toHaveLength(n);
  });

  it('says "no messages" when nothing came after 3 s, and why the robot PC cannot measure', async () => {
    render(InspectPage, { feature, section });
    await showTab('Topics');
    await connect();
    await answerGraph();
    await openTopic('/camera/image_raw');
    statsCalls()[0].ok(STATS({ messages: 0, window_s: 0, rate_hz: 0, bandwidth_bps: 0, last_age_s: -1 }));
    await settle();
    expect(screen.getByTestId('topic-rate').textContent).toBe('measuring…');
    for (let i = 1; i <= 3; i++) {
      await settle(1000);
      statsCalls()[i].ok(STATS({ messages: 0, window_s: i, rate_hz: 0, bandwidth_bps: 0, last_age_s: -1 }));
      await settle();
    }
    expect(screen.getByTestId('topic-rate').textContent).toBe('no messages');
    expect(screen.getByTestId('topic-last').textContent).toBe('none received yet');

    await settle(1000);
    statsCalls()[4].ok({ ok: false, message: 'at most 8 topics are measured at once' });
    await settle();
    expect(screen.getByRole('alert').textContent).toBe('Could not measure /camera/image_raw: at most 8 topics are measured at once');
    expect(screen.getByTestId('topic-rate').textContent).toBe('—');
    // Still asked: the robot PC may have room again.
    await settle(1000);
    expect(statsCalls()).toHaveLength(6);
  });

  it('a missing service is shown in the view, not thrown', async () => {
    render(InspectPage, { feature, section });
    await showTab('Topics');
    await connect();
    graphCalls()[0].fail('Service /cell/inspect/graph does not exist');
    await settle();
    expect(screen.getByTestId('graph-error').textContent).toBe('Could not read the topics: Service /cell/inspect/graph does not exist');
    // Read again on the next round; the error goes once it answers.
    await settle(5000);
    await answerGraph();
    expect(screen.queryByTestId('graph-error')).toBeNull();
    await openTopic('/joint_states');
    statsCalls()[0].fail('Service /cell/inspect/topic_stats does not exist');
    await settle();
    expect(screen.getByTestId('topic-stats-error').textContent).toContain('Service /cell/inspect/topic_stats does not exist');
  });

  it('hides the last message control when the role may not read messages', async () => {
    render(InspectPage, { feature, section });
    await showTab('Topics');
    await connect();
    await answerGraph();
    await openTopic('/joint_states');
    expect(screen.queryByRole('button', { name: 'Show last message' })).toBeNull();
    expect(screen.queryByTestId('topic-echo-toggle')).toBeNull();
    await settle(5000);
    expect(echoCalls()).toHaveLength(0);
  });

  it('can_echo: Show last message asks every 2 s while on and draws the message as a tree', async () => {
    render(InspectPage, { feature, section: echoSection });
    await showTab('Topics');
    await connect();
    await answerGraph();
    await openTopic('/joint_states');
    const toggle = screen.getByRole('button', { name: 'Show last message' });
    expect(toggle.getAttribute('aria-pressed')).toBe('false');
    expect(echoCalls()).toHaveLength(0);

    await fireEvent.click(toggle);
    await settle();
    expect(toggle.getAttribute('aria-pressed')).toBe('true');
    expect(echoCalls()).toHaveLength(1);
    expect(echoCalls()[0].type).toBe('cell_msgs/TopicEcho');
    expect(echoCalls()[0].args).toEqual({ topic: '/joint_states' });
    const msg = {
      header: { seq: 7, stamp: { secs: 1, nsecs: 2 }, frame_id: '' },
      name: ['shoulder_pan_joint', 'elbow_joint'],
      position: [0.1, 0.2, '… 97 more (100 items)'],
      data: '<921600 bytes>',
    };
    echoCalls()[0].ok({ ok: true, message: '', type: 'sensor_msgs/JointState', json: JSON.stringify(msg), age_s: 0.25 });
    await settle();
    const tree = screen.getByTestId('topic-message');
    expect(tree.textContent).toContain('shoulder_pan_joint');
    expect(tree.textContent).toContain('[100 items, first 2 shown]');
    expect(tree.textContent).toContain('"<921600 bytes>"');
    expect(screen.getByTestId('topic-echo-age').textContent).toContain('received 250 ms ago');
    // A collapsible tree: branches are details elements; a branch closed by hand stays closed on the next message.
    const header = /** @type {HTMLDetailsElement} */ ([...tree.querySelectorAll('details')].find((d) => d.querySelector('summary')?.textContent?.startsWith('header')));
    expect(header.open).toBe(true);
    header.open = false;
    await fireEvent(header, new Event('toggle'));

    await settle(2000);
    expect(echoCalls()).toHaveLength(2);
    echoCalls()[1].ok({ ok: true, message: '', type: 'sensor_msgs/JointState', json: JSON.stringify({ ...msg, header: { ...msg.header, seq: 8 } }), age_s: 0.01 });
    await settle();
    expect(header.isConnected).toBe(true);
    expect(header.open).toBe(false);

    await fireEvent.click(toggle);
    await settle();
    expect(toggle.getAttribute('aria-pressed')).toBe('false');
    expect(screen.queryByTestId('topic-message')).toBeNull();
    await settle(10000);
    expect(echoCalls()).toHaveLength(2);
  });

  it('can_echo: a refused call shows the reason and stops; text that is not JSON is shown raw', async () => {
    render(InspectPage, { feature, section: echoSection });
    await showTab('Topics');
    await connect();
    await answerGraph();
    await openTopic('/joint_states');
    const toggle = screen.getByRole('button', { name: 'Show last message' });
    await fireEvent.click(toggle);
    await settle();
    echoCalls()[0].ok({ ok: false, message: 'nothing received yet', type: '', json: '', age_s: -1 });
    await settle();
    expect(screen.getByTestId('topic-echo-status').textContent).toBe('nothing received yet');
    await settle(2000);
    echoCalls()[1].ok({ ok: true, message: '', type: 'x/Y', json: '{"a": nan', age_s: 1 });
    await settle();
    expect(screen.getByTestId('topic-message').querySelector('pre')?.textContent).toBe('{"a": nan');

    await settle(2000);
    echoCalls()[2].fail("the operator role may not read a topic's messages here (the cell file's inspect.echo_roles)");
    await settle();
    expect(screen.getByTestId('topic-echo-error').textContent)
      .toBe("Cannot show the last message: the operator role may not read a topic's messages here (the cell file's inspect.echo_roles)");
    expect(screen.getByTestId('topic-echo-error').getAttribute('role')).toBe('alert');
    expect(toggle.getAttribute('aria-pressed')).toBe('false');
    await settle(10000);
    expect(echoCalls()).toHaveLength(3);
  });
});

describe('Nodes view', () => {
  it('lists the nodes, alive or not responding in words, with their module; a node opens to its topics and services', async () => {
    render(InspectPage, { feature, section });
    await showTab('Nodes');
    await connect();
    await answerGraph();
    const rows = screen.getAllByTestId('node-row');
    expect(rows.map((r) => [r.dataset.node, r.dataset.alive])).toEqual([['/camera_node', 'false'], ['/rosout', 'true'], ['/ur_driver', 'true']]);
    expect(within(rows[0]).getByTestId('node-alive').textContent).toBe('not responding');
    expect(within(rows[2]).getByTestId('node-alive').textContent).toBe('alive');
    expect(within(rows[0]).getByTestId('node-module').textContent).toBe('module camera');
    expect(within(rows[1]).queryByTestId('node-module')).toBeNull();
    expect(screen.getByTestId('node-count').textContent).toBe('3 nodes · 1 not responding');

    const btn = screen.getByRole('button', { name: 'Node /camera_node' });
    expect(btn.getAttribute('aria-expanded')).toBe('false');
    expect(within(rows[0]).queryByTestId('node-info')).toBeNull();
    await fireEvent.click(btn);
    expect(btn.getAttribute('aria-expanded')).toBe('true');
    const info = within(rows[0]).getByTestId('node-info');
    expect(btn.getAttribute('aria-controls')).toBe(info.id);
    expect(within(info).getByRole('list', { name: 'Publications of /camera_node' }).textContent).toContain('/camera/image_raw');
    expect(within(info).getByRole('list', { name: 'Services of /camera_node' }).textContent).toContain('/camera_node/get_loggers');
    expect(info.textContent).toContain('Subscriptions (0)');

    await fireEvent.input(screen.getByRole('searchbox', { name: 'Filter nodes' }), { target: { value: 'ROBOT' } });
    expect(screen.getAllByTestId('node-row').map((r) => r.dataset.node)).toEqual(['/ur_driver']);
    expect(screen.getByTestId('node-count').textContent).toBe('1 of 3 nodes · 1 not responding');
    await fireEvent.input(screen.getByRole('searchbox', { name: 'Filter nodes' }), { target: { value: '' } });

    // A refresh: the driver stopped answering; the opened node stays open.
    await settle(5000);
    expect(graphCalls()).toHaveLength(2);
    await answerGraph({ ...GRAPH, nodes: GRAPH.nodes.map((n) => (n.name === '/ur_driver' ? { ...n, alive: false } : n)) });
    const driver = screen.getAllByTestId('node-row').find((r) => r.dataset.node === '/ur_driver');
    expect(driver?.dataset.alive).toBe('false');
    expect(within(/** @type {HTMLElement} */ (driver)).getByTestId('node-alive').textContent).toBe('not responding');
    expect(screen.getByRole('button', { name: 'Node /camera_node' }).getAttribute('aria-expanded')).toBe('true');

    await fireEvent.click(screen.getByRole('button', { name: 'Refresh nodes' }));
    await settle();
    expect(graphCalls()).toHaveLength(3);
  });

  it('says when ROS is disconnected and stops reading the graph until reconnected', async () => {
    render(InspectPage, { feature, section });
    await showTab('Nodes');
    await connect();
    await answerGraph();
    f.rosList.at(-1)?.emit('close');
    flushSync();
    expect(screen.getByTestId('inspect-not-live').textContent).toContain('ROS disconnected');
    // What was read stays shown.
    expect(screen.getAllByTestId('node-row')).toHaveLength(3);
    const n = graphCalls().length;
    await settle(300); // less than the first reconnect delay
    expect(graphCalls()).toHaveLength(n);
  });
});
