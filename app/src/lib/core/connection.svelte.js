/**
 * The one rosbridge connection of the app (the BFF proxies /ros on the same origin and
 * authenticates it by the session cookie). Pages never open their own sockets: every kind of
 * ROS call goes through here.
 *
 *   ros.subscribe(topic, type, cb, options?)        -> unsubscribe()
 *   ros.advertise(topic, type, options?)            -> { publish(msg), unadvertise() }
 *   ros.publish(topic, type, msg)                   one message on a kept advertisement
 *   ros.callService(name, type, args?, options?)    -> Promise<response values>
 *   ros.actionClient(server, actionType)            -> { sendGoal(goal, handlers?), cancelAll(), dispose() }
 *
 * A fresh Ros object is made for every attempt; after any close/error we retry with exponential
 * backoff and re-issue every live subscription and advertisement on the new socket.
 * Nothing is queued: publishing, calling or sending a goal while not connected fails at once with a
 * NotConnectedError, and calls or goals still waiting when the socket drops fail with
 * ConnectionLostError (their outcome is unknown). Commands never run late.
 */

import { m } from '$lib/paraglide/messages.js';

/** @typedef {'connecting' | 'connected' | 'disconnected'} ConnState */
/**
 * What the connection indicator shows: the state, except that a link that was up and dropped reads
 * 'reconnecting' (the backoff is bringing it back, e.g. while the cell's supervisor restarts a crashed
 * BFF or rosbridge) until it is connected again.
 * @typedef {ConnState | 'reconnecting'} LinkStatus
 */

/**
 * @typedef {object} RosLike  the subset of roslib's Ros we rely on
 * @property {(event: string, fn: (...a: any[]) => void) => any} on
 * @property {(url: string) => Promise<void> | void} connect
 * @property {() => void} close
 */

/**
 * @typedef {object} TopicLike  the subset of roslib's Topic we rely on
 * @property {(cb: (msg: any) => void) => void} subscribe
 * @property {(cb?: (msg: any) => void) => void} unsubscribe
 * @property {() => void} advertise
 * @property {() => void} unadvertise
 * @property {(msg: any) => void} publish
 */

/**
 * @typedef {object} ServiceLike  the subset of roslib's Service we rely on
 * @property {(req: any, ok: (values: any) => void, fail: (error: string) => void) => void} callService
 */

/**
 * @typedef {object} TopicOptions
 * @property {number} [throttle_rate]  ms between messages, applied by rosbridge (subscribe)
 * @property {number} [queue_length]   (subscribe)
 * @property {string} [compression]    (subscribe)
 * @property {boolean} [latch]         (advertise)
 * @property {number} [queue_size]     (advertise)
 */
/** @typedef {TopicOptions} SubscribeOptions */

/**
 * Makes roslib objects. createTopic/createService are only called after createRos resolved,
 * so they may be synchronous.
 * @typedef {object} RosFactory
 * @property {() => RosLike | Promise<RosLike>} createRos
 * @property {(ros: RosLike, name: string, type: string, options: TopicOptions) => TopicLike} createTopic
 * @property {(ros: RosLike, name: string, type: string) => ServiceLike} createService
 */

/** @type {any} */
let roslibModule = null;

/** @type {RosFactory} */
export const roslibFactory = {
  // roslib is loaded lazily so the login screen does not pay for it.
  async createRos() {
    roslibModule ??= await import('roslib');
    return new roslibModule.Ros({});
  },
  createTopic(handle, name, messageType, options) {
    // reconnect_on_close off: we make a new Ros per attempt and restore topics ourselves.
    return new roslibModule.Topic({ ros: /** @type {any} */ (handle), name, messageType, reconnect_on_close: false, ...options });
  },
  createService(handle, name, serviceType) {
    return new roslibModule.Service({ ros: /** @type {any} */ (handle), name, serviceType });
  },
};

/** Raised at once when a command is attempted without a live connection (nothing is queued). */
export class NotConnectedError extends Error {
  /** @param {'command' | 'message' | 'service call' | 'goal'} [what] */
  constructor(what = 'command') {
    super(what === 'message' ? m.core_not_connected_message() : what === 'service call' ? m.core_not_connected_call()
      : what === 'goal' ? m.core_not_connected_goal() : m.core_not_connected_command());
    this.name = 'NotConnectedError';
  }
}

/** The socket dropped before an answer came: the outcome is unknown. */
export class ConnectionLostError extends Error {
  /** @param {'call' | 'goal'} kind @param {string} name  the service, or the action server */
  constructor(kind, name) {
    super(kind === 'goal' ? m.core_lost_goal({ name }) : m.core_lost_call({ name }));
    this.name = 'ConnectionLostError';
  }
}

/** actionlib_msgs/GoalStatus codes. */
export const GOAL_STATUS = Object.freeze({
  PENDING: 0,
  ACTIVE: 1,
  PREEMPTED: 2,
  SUCCEEDED: 3,
  ABORTED: 4,
  REJECTED: 5,
  PREEMPTING: 6,
  RECALLING: 7,
  RECALLED: 8,
  LOST: 9,
});

const STATUS_NAMES = ['pending', 'active', 'preempted', 'succeeded', 'aborted', 'rejected', 'preempting', 'recalling', 'recalled', 'lost'];

/** @param {number} code */
export const goalStatusName = (code) => STATUS_NAMES[code] ?? `status ${code}`;

/** Same-origin rosbridge URL: wss on https pages, ws otherwise. */
export function defaultRosUrl() {
  const loc = globalThis.location;
  if (!loc) return 'ws://127.0.0.1:8080/ros';
  return `${loc.protocol === 'https:' ? 'wss' : 'ws'}://${loc.host}/ros`;
}

/**
 * Delay before reconnect attempt n (0-based): min doubling up to max.
 * @param {number} attempt @param {number} min @param {number} max
 */
export function backoffDelay(attempt, min = 500, max = 8000) {
  return Math.min(max, min * 2 ** Math.max(0, attempt));
}

let goalCounter = 0;

/**
 * @typedef {object} Publisher
 * @property {(msg: any) => void} publish  throws NotConnectedError when not connected
 * @property {() => void} unadvertise
 */

/**
 * @typedef {object} GoalOutcome
 * @property {number} status   a GOAL_STATUS code (SUCCEEDED = 3)
 * @property {string} text     the action server's status text
 * @property {any} result      the action's result message (null if none came)
 */

/**
 * @typedef {object} GoalHandle
 * @property {string} id
 * @property {Promise<GoalOutcome>} result  resolves with the server's outcome (any status);
 *   rejects with ConnectionLostError when the socket drops first, or when the client is disposed
 * @property {() => void} cancel  asks the server to cancel this goal (throws NotConnectedError offline)
 */

/**
 * @typedef {object} ActionClient
 * @property {(goal: any, handlers?: { onFeedback?: (fb: any) => void, onStatus?: (code: number, text: string) => void }) => GoalHandle} sendGoal
 *   throws NotConnectedError when not connected
 * @property {() => void} cancelAll
 * @property {() => void} dispose
 */

export class RosConnection {
  /** @type {ConnState} */
  state = $state('disconnected');
  /**
   * Since when the link has been down (ms since the epoch): set when a socket closes or an attempt
   * fails, kept through the reconnect attempts, null while connected and before the first attempt ends.
   * @type {number | null}
   */
  downSince = $state(null);
  /** The link has been up since start(): a drop now reads 'reconnecting'. Cleared by stop() (logout). */
  wasConnected = $state(false);

  /** @type {Set<{ name: string, type: string, cb: (msg: any) => void, options: TopicOptions, topic: TopicLike | null, gen: number, wrapped?: (m: any) => void }>} */
  #subs = new Set();
  /** @type {Set<{ name: string, type: string, options: TopicOptions, topic: TopicLike | null, gen: number }>} */
  #ads = new Set();
  /** Advertisements kept for ros.publish(), by topic name. @type {Map<string, Publisher>} */
  #shared = new Map();
  /** Whatever must fail when the socket drops (pending calls, running goals). @type {Set<() => void>} */
  #onDown = new Set();
  /** @type {RosLike | null} */
  #ros = null;
  #running = false;
  #attempt = 0;
  // Bumped on every new socket so late events from a dead one are ignored.
  #gen = 0;
  /** @type {any} */
  #timer = null;

  /**
   * @param {object} [opts]
   * @param {RosFactory} [opts.factory]
   * @param {() => string} [opts.url]
   * @param {number} [opts.minDelay]
   * @param {number} [opts.maxDelay]
   * @param {number} [opts.callTimeoutMs]  default time a service call may take (0: none)
   * @param {() => number} [opts.now]
   * @param {(fn: () => void, ms: number) => any} [opts.setTimer]
   * @param {(t: any) => void} [opts.clearTimer]
   */
  constructor(opts = {}) {
    this.factory = opts.factory ?? roslibFactory;
    this.url = opts.url ?? defaultRosUrl;
    this.minDelay = opts.minDelay ?? 500;
    this.maxDelay = opts.maxDelay ?? 8000;
    this.callTimeoutMs = opts.callTimeoutMs ?? 15000;
    this.now = opts.now ?? Date.now;
    this.setTimer = opts.setTimer ?? ((fn, ms) => setTimeout(fn, ms));
    this.clearTimer = opts.clearTimer ?? ((t) => clearTimeout(t));
  }

  /** Number of live subscriptions (for tests and diagnostics). */
  get subscriptionCount() {
    return this.#subs.size;
  }

  /** Number of live advertisements (for tests and diagnostics). */
  get advertisementCount() {
    return this.#ads.size;
  }

  get connected() {
    return this.state === 'connected' && this.#ros !== null;
  }

  /** For the connection indicator: 'reconnecting' when a link that was up is down. @returns {LinkStatus} */
  get status() {
    return this.state !== 'connected' && this.wasConnected ? 'reconnecting' : this.state;
  }

  /** Start connecting (idempotent). Called once the user is logged in. */
  start() {
    if (this.#running) return;
    this.#running = true;
    this.#attempt = 0;
    this.#open();
  }

  /** Close and stop reconnecting (logout). Subscriptions and advertisements are kept for a later start(). */
  stop() {
    this.#running = false;
    if (this.#timer !== null) this.clearTimer(this.#timer);
    this.#timer = null;
    this.#gen++;
    const ros = this.#ros;
    this.#ros = null;
    this.#detachAll();
    this.state = 'disconnected';
    this.downSince = null;
    this.wasConnected = false;
    try {
      ros?.close();
    } catch {
      /* already closed */
    }
  }

  /** Skip the rest of a backoff wait (e.g. the browser just came back online). */
  retryNow() {
    if (!this.#running || this.#timer === null) return;
    this.clearTimer(this.#timer);
    this.#timer = null;
    this.#attempt = 0;
    this.#open();
  }

  /**
   * Subscribe to a topic on the shared connection; survives reconnects.
   * @param {string} name @param {string} type
   * @param {(msg: any) => void} cb
   * @param {SubscribeOptions} [options]
   * @returns {() => void} unsubscribe
   */
  subscribe(name, type, cb, options = {}) {
    /** @type {any} */
    const sub = { name, type, cb, options, topic: null, gen: -1 };
    sub.wrapped = (/** @type {any} */ msg) => sub.cb(msg);
    this.#subs.add(sub);
    if (this.connected) this.#attachSub(sub);
    return () => {
      if (!this.#subs.delete(sub)) return;
      const t = sub.topic;
      sub.topic = null;
      try {
        t?.unsubscribe(sub.wrapped);
      } catch {
        /* socket gone */
      }
    };
  }

  /**
   * Advertise a topic for publishing; the advertisement is re-made after every reconnect.
   * Advertise when the page opens rather than just before the first message: ROS 1 subscribers
   * connect to a new publisher asynchronously and may miss a message sent right away.
   * @param {string} name @param {string} type
   * @param {TopicOptions} [options]
   * @returns {Publisher}
   */
  advertise(name, type, options = {}) {
    /** @type {{ name: string, type: string, options: TopicOptions, topic: TopicLike | null, gen: number }} */
    const ad = { name, type, options, topic: null, gen: -1 };
    this.#ads.add(ad);
    if (this.connected) this.#attachAd(ad);
    return {
      publish: (msg) => {
        if (!this.connected || !ad.topic || ad.gen !== this.#gen || !this.#ads.has(ad)) throw new NotConnectedError('message');
        ad.topic.publish(msg);
      },
      unadvertise: () => {
        if (!this.#ads.delete(ad)) return;
        const t = ad.topic;
        ad.topic = null;
        try {
          t?.unadvertise();
        } catch {
          /* socket gone */
        }
      },
    };
  }

  /**
   * Publish one message; the topic stays advertised (and restored on reconnect) for later ones.
   * Throws NotConnectedError when not connected.
   * @param {string} name @param {string} type @param {any} msg
   */
  publish(name, type, msg) {
    if (!this.connected) throw new NotConnectedError('message');
    let pub = this.#shared.get(name);
    if (!pub) {
      pub = this.advertise(name, type);
      this.#shared.set(name, pub);
    }
    pub.publish(msg);
  }

  /**
   * Call a service. Resolves with the response values; rejects with the backend's message when the
   * call fails (rosbridge `result: false`, e.g. "permission denied"), with NotConnectedError when not
   * connected, with ConnectionLostError when the socket drops first, and after the timeout.
   * @param {string} name @param {string} type @param {any} [args]
   * @param {{ timeoutMs?: number }} [options]  0 = wait as long as the socket lives
   * @returns {Promise<any>}
   */
  callService(name, type, args = {}, options = {}) {
    const ros = this.#ros;
    if (!this.connected || !ros) return Promise.reject(new NotConnectedError('service call'));
    const timeoutMs = options.timeoutMs ?? this.callTimeoutMs;
    return new Promise((resolve, reject) => {
      /** @type {any} */
      let timer = null;
      let done = false;
      const finish = () => {
        done = true;
        this.#onDown.delete(lost);
        if (timer !== null) this.clearTimer(timer);
      };
      const lost = () => {
        if (done) return;
        finish();
        reject(new ConnectionLostError('call', name));
      };
      this.#onDown.add(lost);
      if (timeoutMs > 0) {
        timer = this.setTimer(() => {
          timer = null;
          if (done) return;
          finish();
          reject(new Error(`No answer from ${name} within ${Math.round(timeoutMs / 100) / 10} s`));
        }, timeoutMs);
      }
      try {
        const svc = this.factory.createService(ros, name, type);
        svc.callService(
          args,
          (values) => {
            if (done) return;
            finish();
            resolve(values);
          },
          (error) => {
            if (done) return;
            finish();
            reject(new Error(typeof error === 'string' && error ? error : `Call to ${name} failed`));
          },
        );
      } catch (e) {
        if (!done) {
          finish();
          reject(e instanceof Error ? e : new Error(String(e)));
        }
      }
    });
  }

  /**
   * A ROS 1 actionlib client over topics, as roslib's ActionClient does it (goal and cancel
   * advertised; status, feedback and result subscribed), but on the shared connection so all five
   * channels are restored after a reconnect. Make it when the page opens; dispose() when it closes.
   * @param {string} server  e.g. '/cell/process/run'
   * @param {string} actionType  e.g. 'cell_msgs/RunProcessAction'
   * @returns {ActionClient}
   */
  actionClient(server, actionType) {
    const goalPub = this.advertise(`${server}/goal`, `${actionType}Goal`);
    const cancelPub = this.advertise(`${server}/cancel`, 'actionlib_msgs/GoalID');
    /** @type {Map<string, { resolve: (o: GoalOutcome) => void, reject: (e: Error) => void, onFeedback?: (fb: any) => void, onStatus?: (code: number, text: string) => void, status: number | null, lost: () => void }>} */
    const goals = new Map();
    /** @param {string} id */
    const settle = (id) => {
      const g = goals.get(id);
      if (g) {
        goals.delete(id);
        this.#onDown.delete(g.lost);
      }
      return g;
    };
    /** @param {any} g @param {any} st */
    const noteStatus = (g, st) => {
      if (!st || typeof st.status !== 'number' || st.status === g.status) return;
      g.status = st.status;
      g.onStatus?.(st.status, st.text ?? '');
    };
    const unsubs = [
      this.subscribe(`${server}/status`, 'actionlib_msgs/GoalStatusArray', (m) => {
        for (const st of m?.status_list ?? []) {
          const g = goals.get(st?.goal_id?.id);
          if (g) noteStatus(g, st);
        }
      }),
      this.subscribe(`${server}/feedback`, `${actionType}Feedback`, (m) => {
        const g = goals.get(m?.status?.goal_id?.id);
        if (!g) return;
        noteStatus(g, m.status);
        g.onFeedback?.(m.feedback);
      }),
      this.subscribe(`${server}/result`, `${actionType}Result`, (m) => {
        const id = m?.status?.goal_id?.id;
        const g = goals.get(id);
        if (!g) return;
        noteStatus(g, m.status);
        settle(id);
        g.resolve({ status: m.status.status, text: m.status.text ?? '', result: m.result ?? null });
      }),
    ];
    let disposed = false;
    const zeroStamp = () => ({ secs: 0, nsecs: 0 });

    return {
      sendGoal: (goal, handlers = {}) => {
        if (disposed) throw new Error(`The action client for ${server} is closed`);
        if (!this.connected) throw new NotConnectedError('goal');
        const id = `goal_${Date.now().toString(36)}_${(goalCounter++).toString(36)}_${Math.random().toString(36).slice(2, 8)}`;
        /** @type {(o: GoalOutcome) => void} */
        let resolve = () => {};
        /** @type {(e: Error) => void} */
        let reject = () => {};
        const result = /** @type {Promise<GoalOutcome>} */ (new Promise((res, rej) => ((resolve = res), (reject = rej))));
        const lost = () => {
          if (settle(id)) reject(new ConnectionLostError('goal', server));
        };
        goals.set(id, { resolve, reject, onFeedback: handlers.onFeedback, onStatus: handlers.onStatus, status: null, lost });
        this.#onDown.add(lost);
        try {
          goalPub.publish({ goal_id: { stamp: zeroStamp(), id }, goal });
        } catch (e) {
          settle(id);
          throw e;
        }
        return { id, result, cancel: () => cancelPub.publish({ stamp: zeroStamp(), id }) };
      },
      cancelAll: () => cancelPub.publish({ stamp: zeroStamp(), id: '' }),
      dispose: () => {
        if (disposed) return;
        disposed = true;
        for (const u of unsubs) u();
        goalPub.unadvertise();
        cancelPub.unadvertise();
        for (const [id, g] of [...goals]) {
          settle(id);
          g.reject(new Error(`The action client for ${server} was closed before the goal ended`));
        }
      },
    };
  }

  async #open() {
    const gen = ++this.#gen;
    this.state = 'connecting';
    let ros;
    try {
      ros = await this.factory.createRos();
    } catch {
      if (gen === this.#gen) this.#scheduleRetry(gen);
      return;
    }
    if (gen !== this.#gen || !this.#running) {
      ros.close?.();
      return;
    }
    this.#ros = ros;
    ros.on('connection', () => {
      if (gen !== this.#gen) return;
      this.#attempt = 0;
      this.state = 'connected';
      this.downSince = null;
      this.wasConnected = true;
      for (const a of this.#ads) this.#attachAd(a);
      for (const s of this.#subs) this.#attachSub(s);
    });
    const down = () => this.#scheduleRetry(gen);
    ros.on('close', down);
    ros.on('error', down);
    try {
      await ros.connect(this.url());
    } catch {
      down();
    }
  }

  /** Forget the dead socket's topics and fail whatever waited for an answer on it. */
  #detachAll() {
    for (const s of this.#subs) s.topic = null;
    for (const a of this.#ads) a.topic = null;
    const waiting = [...this.#onDown];
    this.#onDown.clear();
    for (const fn of waiting) fn();
  }

  /** @param {number} gen */
  #scheduleRetry(gen) {
    // close and error often both fire for one failure: only the first counts.
    if (gen !== this.#gen || !this.#running) return;
    this.#gen++;
    const old = this.#ros;
    this.#ros = null;
    this.state = 'disconnected';
    this.downSince ??= this.now();
    this.#detachAll();
    try {
      old?.close();
    } catch {
      /* ignore */
    }
    const delay = backoffDelay(this.#attempt++, this.minDelay, this.maxDelay);
    this.#timer = this.setTimer(() => {
      this.#timer = null;
      if (this.#running) this.#open();
    }, delay);
  }

  /** @param {any} sub */
  #attachSub(sub) {
    const ros = this.#ros;
    if (!ros || sub.gen === this.#gen) return;
    sub.gen = this.#gen;
    try {
      const topic = this.factory.createTopic(ros, sub.name, sub.type, sub.options);
      sub.topic = topic;
      topic.subscribe(sub.wrapped);
    } catch {
      sub.topic = null;
    }
  }

  /** @param {{ name: string, type: string, options: TopicOptions, topic: TopicLike | null, gen: number }} ad */
  #attachAd(ad) {
    const ros = this.#ros;
    if (!ros || ad.gen === this.#gen) return;
    ad.gen = this.#gen;
    try {
      const topic = this.factory.createTopic(ros, ad.name, ad.type, ad.options);
      ad.topic = topic;
      topic.advertise();
    } catch {
      ad.topic = null;
    }
  }
}

/** The app-wide connection. */
export const ros = new RosConnection();
