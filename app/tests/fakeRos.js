/** Test doubles for roslib's Ros and Topic, injected through RosConnection's factory. */
export function makeFakeFactory() {
  /** @type {FakeRos[]} */
  const rosList = [];
  /** @type {FakeTopic[]} */
  const topics = [];

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
    /** @param {FakeRos} ros @param {string} name @param {string} type @param {any} options */
    constructor(ros, name, type, options) {
      Object.assign(this, { ros, name, type, options });
    }
    /** @param {Function} cb */
    subscribe(cb) {
      this.callbacks.push(cb);
    }
    unsubscribe() {
      this.unsubscribed = true;
      this.callbacks = [];
    }
    /** @param {any} msg */
    deliver(msg) {
      for (const cb of this.callbacks) cb(msg);
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
  };
  return { factory, rosList, topics };
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
