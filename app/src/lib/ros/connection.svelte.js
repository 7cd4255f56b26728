/**
 * The one rosbridge connection of the app (the BFF proxies /ros on the same origin and
 * authenticates it by the session cookie). Pages never open their own sockets: they call
 * `ros.subscribe(...)` and get an unsubscribe function back.
 *
 * A fresh Ros object is made for every attempt; after any close/error we retry with
 * exponential backoff and re-issue every live subscription on the new socket.
 */

/** @typedef {'connecting' | 'connected' | 'disconnected'} ConnState */

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
 */

/**
 * @typedef {object} SubscribeOptions
 * @property {number} [throttle_rate]  ms between messages, applied by rosbridge
 * @property {number} [queue_length]
 * @property {string} [compression]
 */

/**
 * @typedef {object} RosFactory
 * @property {() => RosLike | Promise<RosLike>} createRos
 * @property {(ros: RosLike, name: string, type: string, options: SubscribeOptions) => TopicLike | Promise<TopicLike>} createTopic
 */

/** @type {RosFactory} */
export const roslibFactory = {
  // roslib is loaded lazily so the login screen does not pay for it.
  async createRos() {
    const { Ros } = await import('roslib');
    return new Ros({});
  },
  async createTopic(handle, name, messageType, options) {
    const { Topic } = await import('roslib');
    /** @type {any} */
    const rosObj = handle;
    // reconnect_on_close off: we make a new Ros per attempt and re-subscribe ourselves.
    return new Topic({ ros: rosObj, name, messageType, reconnect_on_close: false, ...options });
  },
};

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

export class RosConnection {
  /** @type {ConnState} */
  state = $state('disconnected');

  /** @type {Set<{ name: string, type: string, cb: (msg: any) => void, options: SubscribeOptions, topic: TopicLike | null, gen: number }>} */
  #subs = new Set();
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
   * @param {(fn: () => void, ms: number) => any} [opts.setTimer]
   * @param {(t: any) => void} [opts.clearTimer]
   */
  constructor(opts = {}) {
    this.factory = opts.factory ?? roslibFactory;
    this.url = opts.url ?? defaultRosUrl;
    this.minDelay = opts.minDelay ?? 500;
    this.maxDelay = opts.maxDelay ?? 8000;
    this.setTimer = opts.setTimer ?? ((fn, ms) => setTimeout(fn, ms));
    this.clearTimer = opts.clearTimer ?? ((t) => clearTimeout(t));
  }

  /** Number of live subscriptions (for tests and diagnostics). */
  get subscriptionCount() {
    return this.#subs.size;
  }

  /** Start connecting (idempotent). Called once the user is logged in. */
  start() {
    if (this.#running) return;
    this.#running = true;
    this.#attempt = 0;
    this.#open();
  }

  /** Close and stop reconnecting (logout). Subscriptions are kept for a later start(). */
  stop() {
    this.#running = false;
    if (this.#timer !== null) this.clearTimer(this.#timer);
    this.#timer = null;
    this.#gen++;
    const ros = this.#ros;
    this.#ros = null;
    for (const s of this.#subs) s.topic = null;
    this.state = 'disconnected';
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
    this.#subs.add(sub);
    if (this.state === 'connected' && this.#ros) this.#attach(sub, this.#ros, this.#gen);
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
      for (const s of this.#subs) this.#attach(s, ros, gen);
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

  /** @param {number} gen */
  #scheduleRetry(gen) {
    // close and error often both fire for one failure: only the first counts.
    if (gen !== this.#gen || !this.#running) return;
    this.#gen++;
    const old = this.#ros;
    this.#ros = null;
    for (const s of this.#subs) s.topic = null;
    try {
      old?.close();
    } catch {
      /* ignore */
    }
    this.state = 'disconnected';
    const delay = backoffDelay(this.#attempt++, this.minDelay, this.maxDelay);
    this.#timer = this.setTimer(() => {
      this.#timer = null;
      if (this.#running) this.#open();
    }, delay);
  }

  /**
   * @param {any} sub
   * @param {RosLike} ros
   * @param {number} gen
   */
  async #attach(sub, ros, gen) {
    if (sub.gen === gen) return;
    sub.gen = gen;
    sub.wrapped ??= (/** @type {any} */ msg) => sub.cb(msg);
    const topic = await this.factory.createTopic(ros, sub.name, sub.type, sub.options);
    // The socket may have died or the caller unsubscribed while the factory was loading.
    if (gen !== this.#gen || !this.#subs.has(sub)) return;
    sub.topic = topic;
    topic.subscribe(sub.wrapped);
  }
}

/** The app-wide connection. */
export const ros = new RosConnection();
