/** Test doubles for roslib's Ros, Topic and Service, injected through RosConnection's factory. */
export function makeFakeFactory() {
  /** @type {FakeRos[]} */
  const rosList = [];
  /** @type {FakeTopic[]} */
  const topics = [];
  /** @type {FakeCall[]} */
  const calls = [];

  class FakeRos {
    /** @type {Record<string, Function[]>} */
    handlers = {};
    closed = false;
    /** @type {string | null} */
    url = null;
    /** @param {string} ev @param {Function} fn */
    on(ev, fn) {
      (this.handlers[ev] ??= []).push(fn);
    }
    /** @param {string} ev @param {...any} a */
    emit(ev, ...a) {
      for (const fn of this.handlers[ev] ?? []) fn(...a);
    }
    /** @param {string} url */
    connect(url) {
      this.url = url;
      return Promise.resolve();
    }
    close() {
      this.closed = true;
    }
  }

  class FakeTopic {
    /** @type {Function[]} */
    callbacks = [];
    unsubscribed = false;
    advertised = false;
    unadvertised = false;
    /** @type {any[]} */
    published = [];
    /** @param {FakeRos} ros @param {string} name @param {string} type @param {any} options */
    constructor(ros, name, type, options) {
      /** @type {FakeRos} */ this.ros = ros;
      /** @type {string} */ this.name = name;
      /** @type {string} */ this.type = type;
      /** @type {any} */ this.options = options;
    }
    /** @param {Function} cb */
    subscribe(cb) {
      this.callbacks.push(cb);
    }
    unsubscribe() {
      this.unsubscribed = true;
      this.callbacks = [];
    }
    advertise() {
      this.advertised = true;
    }
    unadvertise() {
      this.unadvertised = true;
      this.advertised = false;
    }
    /** @param {any} msg */
    publish(msg) {
      if (this.ros.closed) throw new Error('publish on a closed socket');
      this.published.push(msg);
    }
    /** @param {any} msg */
    deliver(msg) {
      for (const cb of this.callbacks) cb(msg);
    }
  }

  /** One service call the test answers with ok(values) or fail(message). */
  class FakeCall {
    /** @param {FakeRos} ros @param {string} name @param {string} type @param {any} args @param {Function} okCb @param {Function} failCb */
    constructor(ros, name, type, args, okCb, failCb) {
      /** @type {FakeRos} */ this.ros = ros;
      /** @type {string} */ this.name = name;
      /** @type {string} */ this.type = type;
      /** @type {any} */ this.args = args;
      this.ok = /** @param {any} values */ (values) => okCb(values);
      this.fail = /** @param {string} message */ (message) => failCb(message);
    }
  }

  const factory = {
    createRos() {
      const r = new FakeRos();
      rosList.push(r);
      return r;
    },
    /** @param {any} ros @param {string} name @param {string} type @param {any} options */
    createTopic(ros, name, type, options) {
      const t = new FakeTopic(ros, name, type, options);
      topics.push(t);
      return t;
    },
    /** @param {any} ros @param {string} name @param {string} type */
    createService(ros, name, type) {
      return {
        /** @param {any} args @param {Function} ok @param {Function} fail */
        callService(args, ok, fail) {
          calls.push(new FakeCall(ros, name, type, args, ok, fail));
        },
      };
    },
  };
  /** @param {string} name the live topics with this name (newest last) */
  const topicsNamed = (name) => topics.filter((t) => t.name === name);
  return { factory, rosList, topics, calls, topicsNamed };
}

/** Manual timers so backoff delays can be asserted without waiting. */
export function makeFakeTimers() {
  /** @type {{ fn: () => void, ms: number, id: number }[]} */
  const pending = [];
  let next = 1;
  return {
    pending,
    /** @param {() => void} fn @param {number} ms */
    setTimer(fn, ms) {
      const id = next++;
      pending.push({ fn, ms, id });
      return id;
    },
    /** @param {number} id */
    clearTimer(id) {
      const i = pending.findIndex((p) => p.id === id);
      if (i >= 0) pending.splice(i, 1);
    },
    /** Run the oldest pending timer; returns its delay. */
    runNext() {
      const t = pending.shift();
      if (!t) throw new Error('no pending timer');
      t.fn();
      return t.ms;
    },
  };
}

/** Let queued promise callbacks run (factory calls are awaited). */
export const flush = () => new Promise((r) => setTimeout(r, 0));

/**
 * A RosConnection wired to the fakes, plus a helper that opens the socket.
 * @param {typeof import('../src/lib/core/connection.svelte.js').RosConnection} RosConnection
 * @param {object} [opts]
 */
export function fakeConnection(RosConnection, opts = {}) {
  const f = makeFakeFactory();
  const timers = makeFakeTimers();
  const conn = new RosConnection({
    factory: f.factory,
    url: () => 'ws://test/ros',
    setTimer: timers.setTimer,
    clearTimer: timers.clearTimer,
    ...opts,
  });
  const connect = async () => {
    conn.start();
    await flush();
    f.rosList.at(-1)?.emit('connection');
  };
  return { ...f, timers, conn, connect };
}
