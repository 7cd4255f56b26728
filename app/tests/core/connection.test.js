// @vitest-environment node
import { describe, it, expect, vi } from 'vitest';
import {
  RosConnection,
  backoffDelay,
  defaultRosUrl,
  NotConnectedError,
  ConnectionLostError,
  GOAL_STATUS,
  goalStatusName,
} from '../../src/lib/core/connection.svelte.js';
import { makeFakeFactory, makeFakeTimers, flush, fakeConnection } from '../fakeRos.js';
import { render } from 'svelte/server';
import ConnStatus from '../../src/lib/ui/ConnStatus.svelte';

function setup() {
  const f = makeFakeFactory();
  const timers = makeFakeTimers();
  const conn = new RosConnection({
    factory: f.factory,
    url: () => 'ws://test/ros',
    setTimer: timers.setTimer,
    clearTimer: timers.clearTimer,
  });
  return { ...f, timers, conn };
}

describe('backoffDelay', () => {
  it('doubles from 0.5 s and caps at 8 s', () => {
    expect([0, 1, 2, 3, 4, 5, 9].map((n) => backoffDelay(n))).toEqual([500, 1000, 2000, 4000, 8000, 8000, 8000]);
  });
});

describe('defaultRosUrl', () => {
  it('uses the page origin with /ros: ws on http, wss on https', () => {
    vi.stubGlobal('location', { protocol: 'http:', host: 'cell.local:8080' });
    expect(defaultRosUrl()).toBe('ws://cell.local:8080/ros');
    vi.stubGlobal('location', { protocol: 'https:', host: 'cell.local:8443' });
    expect(defaultRosUrl()).toBe('wss://cell.local:8443/ros');
    vi.unstubAllGlobals();
  });
});

describe('ConnStatus', () => {
  /** @param {{ state: import('../../src/lib/core/connection.svelte.js').LinkStatus }} props */
  const shown = (props) => render(ConnStatus, { props: { testid: 'c', ...props } }).body.match(/data-testid="c"[^>]*>([^<]*)</)?.[1];

  it('shows the status it is given, reconnecting included', () => {
    for (const state of /** @type {const} */ (['connecting', 'connected', 'disconnected', 'reconnecting'])) {
      expect(shown({ state })).toBe(state);
    }
  });
});

describe('RosConnection', () => {
  it('goes connecting -> connected and connects to the given url', async () => {
    const { conn, rosList } = setup();
    expect(conn.state).toBe('disconnected');
    conn.start();
    expect(conn.state).toBe('connecting');
    await flush();
    expect(rosList).toHaveLength(1);
    expect(rosList[0].url).toBe('ws://test/ros');
    rosList[0].emit('connection');
    expect(conn.state).toBe('connected');
  });

  it('reconnects with exponential backoff, resets after success', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    const delays = [];
    for (let i = 0; i < 6; i++) {
      const r = /** @type {any} */ (rosList.at(-1));
      r.emit('error');
      r.emit('close'); // both fire for one failure: must schedule only one retry
      expect(conn.state).toBe('disconnected');
      expect(timers.pending).toHaveLength(1);
      delays.push(timers.runNext());
      await flush();
    }
    expect(delays).toEqual([500, 1000, 2000, 4000, 8000, 8000]);
    expect(rosList).toHaveLength(7);
    expect(rosList.slice(0, 6).every((r) => r.closed)).toBe(true);

    rosList[rosList.length - 1].emit('connection');
    expect(conn.state).toBe('connected');
    rosList[rosList.length - 1].emit('close');
    expect(timers.runNext()).toBe(500);
  });

  it('re-issues every live subscription after a reconnect, not the dropped ones', async () => {
    const { conn, rosList, topics, timers } = setup();
    /** @type {[string, string][]} */
    const got = [];
    const unsubA = conn.subscribe('/cell/mode', 'cell_msgs/OperationMode', (m) => got.push(['a', m.mode]));
    conn.subscribe('/other', 'std_msgs/String', (m) => got.push(['b', m.data]), { throttle_rate: 100 });
    conn.start();
    await flush();
    rosList[0].emit('connection');
    await flush();
    expect(topics.map((t) => t.name)).toEqual(['/cell/mode', '/other']);
    expect(topics[1].options).toEqual({ throttle_rate: 100 });
    topics[0].deliver({ mode: 'running' });

    unsubA();
    expect(topics[0].unsubscribed).toBe(true);
    expect(conn.subscriptionCount).toBe(1);

    rosList[0].emit('close');
    timers.runNext();
    await flush();
    rosList[1].emit('connection');
    await flush();
    // Only /other is re-subscribed, on the new socket.
    expect(topics.map((t) => t.name)).toEqual(['/cell/mode', '/other', '/other']);
    expect(topics[2].ros).toBe(rosList[1]);
    topics[2].deliver({ data: 'x' });
    expect(got).toEqual([['a', 'running'], ['b', 'x']]);
  });

  it('a subscription made while connected attaches immediately', async () => {
    const { conn, rosList, topics } = setup();
    conn.start();
    await flush();
    rosList[0].emit('connection');
    conn.subscribe('/late', 'std_msgs/String', () => {});
    await flush();
    expect(topics.map((t) => t.name)).toEqual(['/late']);
  });

  it('ignores events from a dead socket', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    const old = rosList[0];
    old.emit('close');
    timers.runNext();
    await flush();
    old.emit('connection'); // late event from the first socket
    expect(conn.state).toBe('connecting');
    old.emit('close');
    expect(timers.pending).toHaveLength(0);
  });

  it('stop() closes the socket and does not reconnect (logout)', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    rosList[0].emit('connection');
    conn.stop();
    expect(rosList[0].closed).toBe(true);
    expect(conn.state).toBe('disconnected');
    rosList[0].emit('close');
    expect(timers.pending).toHaveLength(0);
  });

  it("a dropped link that was up reads 'reconnecting' (through every attempt) until it is connected again", async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    expect(conn.status).toBe('connecting'); // the very first attempt
    await flush();
    rosList[0].emit('close');
    expect(conn.status).toBe('disconnected'); // never connected yet: the backend may be off
    timers.runNext();
    await flush();
    rosList[1].emit('connection');
    expect([conn.state, conn.status, conn.wasConnected]).toEqual(['connected', 'connected', true]);
    rosList[1].emit('close'); // e.g. the BFF was killed and the cell's supervisor restarts it
    expect([conn.state, conn.status]).toEqual(['disconnected', 'reconnecting']);
    expect(conn.downSince).not.toBeNull(); // the offline / last-known notices work as before
    timers.runNext();
    expect([conn.state, conn.status]).toEqual(['connecting', 'reconnecting']);
    await flush();
    rosList[2].emit('error'); // the BFF is not back yet
    timers.runNext();
    await flush();
    expect(conn.status).toBe('reconnecting');
    rosList[3].emit('connection');
    expect([conn.state, conn.status, conn.downSince]).toEqual(['connected', 'connected', null]);
  });

  it("stop() (logout) forgets that the link was up: the next start reads 'connecting'", async () => {
    const { conn, rosList } = setup();
    conn.start();
    await flush();
    rosList[0].emit('connection');
    conn.stop();
    expect([conn.status, conn.wasConnected]).toEqual(['disconnected', false]);
    conn.start();
    expect(conn.status).toBe('connecting');
  });

  it('stop() during a backoff wait cancels the retry', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    rosList[0].emit('close');
    expect(timers.pending).toHaveLength(1);
    conn.stop();
    expect(timers.pending).toHaveLength(0);
  });

  it('retryNow() skips the backoff wait and resets the delay', async () => {
    const { conn, rosList, timers } = setup();
    conn.start();
    await flush();
    rosList[0].emit('close');
    timers.runNext();
    await flush();
    rosList[1].emit('close'); // now waiting 1 s
    expect(timers.pending[0].ms).toBe(1000);
    conn.retryNow();
    expect(timers.pending).toHaveLength(0);
    expect(conn.state).toBe('connecting');
    await flush();
    expect(rosList).toHaveLength(3);
    rosList[2].emit('close');
    expect(timers.pending[0].ms).toBe(500);
  });
});

/**
 * Drop the socket and bring a new one up (runs the backoff timer).
 * @param {{ rosList: { emit: (ev: string) => void }[], timers: { runNext: () => number } }} t
 */
async function reconnect(t) {
  t.rosList.at(-1)?.emit('close');
  t.timers.runNext();
  await flush();
  t.rosList.at(-1)?.emit('connection');
}

describe('RosConnection: publish and advertise', () => {
  it('advertises on connect, publishes on the socket, and re-advertises after a reconnect', async () => {
    const t = fakeConnection(RosConnection);
    const pub = t.conn.advertise('/cell/jog', 'cell_msgs/Jog', { queue_size: 1 });
    expect(() => pub.publish({ axis: 'x' })).toThrow(NotConnectedError);
    await t.connect();
    const [first] = t.topicsNamed('/cell/jog');
    expect(first).toMatchObject({ type: 'cell_msgs/Jog', advertised: true, options: { queue_size: 1 } });
    pub.publish({ axis: 'x' });
    expect(first.published).toEqual([{ axis: 'x' }]);

    t.rosList[0].emit('close');
    // Nothing is queued while down.
    expect(() => pub.publish({ axis: 'y' })).toThrow(/not sent/);
    t.timers.runNext();
    await flush();
    t.rosList[1].emit('connection');
    const second = t.topicsNamed('/cell/jog')[1];
    expect(second.ros).toBe(t.rosList[1]);
    expect(second.advertised).toBe(true);
    pub.publish({ axis: 'z' });
    expect(second.published).toEqual([{ axis: 'z' }]);
    expect(first.published).toEqual([{ axis: 'x' }]);

    pub.unadvertise();
    expect(second.unadvertised).toBe(true);
    expect(t.conn.advertisementCount).toBe(0);
    expect(() => pub.publish({ axis: 'x' })).toThrow(NotConnectedError);
  });

  it('ros.publish keeps one advertisement per topic and refuses while disconnected', async () => {
    const t = fakeConnection(RosConnection);
    expect(() => t.conn.publish('/cell/cmd', 'std_msgs/String', { data: 'a' })).toThrow(NotConnectedError);
    expect(t.conn.advertisementCount).toBe(0);
    await t.connect();
    t.conn.publish('/cell/cmd', 'std_msgs/String', { data: 'a' });
    t.conn.publish('/cell/cmd', 'std_msgs/String', { data: 'b' });
    expect(t.topicsNamed('/cell/cmd')).toHaveLength(1);
    expect(t.topicsNamed('/cell/cmd')[0].published).toEqual([{ data: 'a' }, { data: 'b' }]);
    await reconnect(t);
    t.conn.publish('/cell/cmd', 'std_msgs/String', { data: 'c' });
    expect(t.topicsNamed('/cell/cmd')[1].published).toEqual([{ data: 'c' }]);
  });

  it('subscriptions and advertisements share the one socket', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    t.conn.subscribe('/a', 'std_msgs/String', () => {});
    t.conn.advertise('/b', 'std_msgs/String');
    const p = t.conn.callService('/c', 'std_srvs/Trigger');
    t.calls[0].ok({ success: true });
    await p;
    expect(t.calls[0].ros).toBe(t.rosList[0]);
    expect(t.rosList).toHaveLength(1);
    expect(t.topics.every((x) => x.ros === t.rosList[0])).toBe(true);
  });
});

describe('RosConnection: service calls', () => {
  it('resolves with the response values', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    const p = t.conn.callService('/cell/get_mode', 'cell_msgs/GetMode', { x: 1 });
    expect(t.calls[0]).toMatchObject({ name: '/cell/get_mode', type: 'cell_msgs/GetMode', args: { x: 1 } });
    t.calls[0].ok({ mode: 'idle' });
    await expect(p).resolves.toEqual({ mode: 'idle' });
  });

  it("rejects with the backend's message", async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    const p = t.conn.callService('/cell/set_mode', 'cell_msgs/SetMode', { mode: 'running' });
    t.calls[0].fail('permission denied: role "operator" may not call /cell/set_mode');
    await expect(p).rejects.toThrow('permission denied: role "operator" may not call /cell/set_mode');
  });

  it('rejects at once when not connected: nothing is queued', async () => {
    const t = fakeConnection(RosConnection);
    await expect(t.conn.callService('/cell/stop', 'std_srvs/Trigger')).rejects.toBeInstanceOf(NotConnectedError);
    t.conn.start();
    await flush();
    // connecting, not yet connected
    await expect(t.conn.callService('/cell/stop', 'std_srvs/Trigger')).rejects.toThrow(/not sent/);
    t.rosList[0].emit('connection');
    expect(t.calls).toHaveLength(0);
  });

  it('a call pending when the socket drops fails as lost; a late answer is ignored', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    const p = t.conn.callService('/cell/slow', 'std_srvs/Trigger');
    t.rosList[0].emit('close');
    await expect(p).rejects.toBeInstanceOf(ConnectionLostError);
    t.calls[0].ok({ success: true }); // must not throw or resolve anything
  });

  it('times out without an answer and clears its timer when answered', async () => {
    const t = fakeConnection(RosConnection, { callTimeoutMs: 5000 });
    await t.connect();
    const p = t.conn.callService('/cell/slow', 'std_srvs/Trigger');
    expect(t.timers.pending.map((x) => x.ms)).toEqual([5000]);
    t.timers.runNext();
    await expect(p).rejects.toThrow('No answer from /cell/slow within 5 s');

    const q = t.conn.callService('/cell/fast', 'std_srvs/Trigger', {}, { timeoutMs: 0 });
    expect(t.timers.pending).toHaveLength(0);
    t.calls[1].ok({ success: true, message: '' });
    await expect(q).resolves.toEqual({ success: true, message: '' });

    const r = t.conn.callService('/cell/fast', 'std_srvs/Trigger');
    t.calls[2].ok({});
    await r;
    expect(t.timers.pending).toHaveLength(0);
  });
});

describe('RosConnection: actionlib goals', () => {
  const server = '/cell/process/run';
  const type = 'cell_msgs/RunProcessAction';

  it('advertises goal/cancel and subscribes status/feedback/result on the shared socket', async () => {
    const t = fakeConnection(RosConnection);
    const client = t.conn.actionClient(server, type);
    await t.connect();
    expect(t.topics.map((x) => [x.name, x.type])).toEqual([
      [`${server}/goal`, `${type}Goal`],
      [`${server}/cancel`, 'actionlib_msgs/GoalID'],
      [`${server}/status`, 'actionlib_msgs/GoalStatusArray'],
      [`${server}/feedback`, `${type}Feedback`],
      [`${server}/result`, `${type}Result`],
    ]);
    expect(t.topicsNamed(`${server}/goal`)[0].advertised).toBe(true);
    expect(t.topicsNamed(`${server}/result`)[0].callbacks).toHaveLength(1);
    client.dispose();
    expect(t.conn.subscriptionCount).toBe(0);
    expect(t.conn.advertisementCount).toBe(0);
  });

  it('sends a goal, reports status and feedback, resolves with the result', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    const client = t.conn.actionClient(server, type);
    /** @type {any[]} */
    const feedback = [];
    /** @type {[number, string][]} */
    const statuses = [];
    const g = client.sendGoal({ steps: 2 }, { onFeedback: (f) => feedback.push(f), onStatus: (c, text) => statuses.push([c, text]) });
    const goalTopic = t.topicsNamed(`${server}/goal`)[0];
    expect(goalTopic.published).toEqual([{ goal_id: { stamp: { secs: 0, nsecs: 0 }, id: g.id }, goal: { steps: 2 } }]);

    const st = (/** @type {number} */ status, text = '') => ({ goal_id: { id: g.id, stamp: { secs: 1, nsecs: 0 } }, status, text });
    t.topicsNamed(`${server}/status`)[0].deliver({ status_list: [st(GOAL_STATUS.ACTIVE), { goal_id: { id: 'other' }, status: 4 }] });
    t.topicsNamed(`${server}/feedback`)[0].deliver({ status: st(GOAL_STATUS.ACTIVE), feedback: { step: 1 } });
    t.topicsNamed(`${server}/feedback`)[0].deliver({ status: { goal_id: { id: 'other' }, status: 1 }, feedback: { step: 99 } });
    t.topicsNamed(`${server}/result`)[0].deliver({ status: { goal_id: { id: 'other' }, status: 3 }, result: {} });
    t.topicsNamed(`${server}/result`)[0].deliver({ status: st(GOAL_STATUS.SUCCEEDED, 'done'), result: { parts: 2 } });
    await expect(g.result).resolves.toEqual({ status: 3, text: 'done', result: { parts: 2 } });
    expect(feedback).toEqual([{ step: 1 }]);
    expect(statuses).toEqual([[1, ''], [3, 'done']]);
    expect(goalStatusName(3)).toBe('succeeded');
  });

  it('an aborted goal resolves with its status and the server text', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    const client = t.conn.actionClient(server, type);
    const g = client.sendGoal({});
    t.topicsNamed(`${server}/result`)[0].deliver({ status: { goal_id: { id: g.id }, status: GOAL_STATUS.ABORTED, text: 'gripper jammed' }, result: null });
    await expect(g.result).resolves.toMatchObject({ status: 4, text: 'gripper jammed' });
  });

  it('cancels one goal or all goals over the cancel topic', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    const client = t.conn.actionClient(server, type);
    const g = client.sendGoal({});
    g.cancel();
    client.cancelAll();
    expect(t.topicsNamed(`${server}/cancel`)[0].published).toEqual([
      { stamp: { secs: 0, nsecs: 0 }, id: g.id },
      { stamp: { secs: 0, nsecs: 0 }, id: '' },
    ]);
  });

  it('refuses a goal while disconnected; a running goal fails as lost when the socket drops', async () => {
    const t = fakeConnection(RosConnection);
    const client = t.conn.actionClient(server, type);
    expect(() => client.sendGoal({})).toThrow(NotConnectedError);
    await t.connect();
    const g = client.sendGoal({});
    t.rosList[0].emit('close');
    await expect(g.result).rejects.toBeInstanceOf(ConnectionLostError);
    expect(() => g.cancel()).toThrow(NotConnectedError);
  });

  it('restores all five channels after a reconnect and works on the new socket', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    const client = t.conn.actionClient(server, type);
    await reconnect(t);
    for (const ch of ['goal', 'cancel', 'status', 'feedback', 'result']) {
      const list = t.topicsNamed(`${server}/${ch}`);
      expect(list, ch).toHaveLength(2);
      expect(list[1].ros).toBe(t.rosList[1]);
    }
    const g = client.sendGoal({ n: 1 });
    expect(t.topicsNamed(`${server}/goal`)[1].published).toHaveLength(1);
    t.topicsNamed(`${server}/result`)[1].deliver({ status: { goal_id: { id: g.id }, status: 3, text: '' }, result: { ok: true } });
    await expect(g.result).resolves.toMatchObject({ status: 3, result: { ok: true } });
  });

  it('dispose fails the goals still running', async () => {
    const t = fakeConnection(RosConnection);
    await t.connect();
    const client = t.conn.actionClient(server, type);
    const g = client.sendGoal({});
    client.dispose();
    await expect(g.result).rejects.toThrow(/closed before the goal ended/);
    expect(() => client.sendGoal({})).toThrow(/closed/);
  });
});
