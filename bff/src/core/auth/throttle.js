// Login throttling: after `max` failures for a user name or an address within `windowMs`, further attempts
// for that key are refused for `cooldownMs`, whether or not the user exists.

export class LoginThrottle {
  /** @param {{max?: number, windowMs?: number, cooldownMs?: number, now?: () => number}} [o] */
  constructor({ max = 5, windowMs = 5 * 60_000, cooldownMs = 5 * 60_000, now = Date.now } = {}) {
    this.max = max;
    this.windowMs = windowMs;
    this.cooldownMs = cooldownMs;
    this.now = now;
    /** @type {Map<string, {fails: number[], until: number}>} */
    this.keys = new Map();
  }

  /** Seconds to wait before another attempt for any of these keys (0: go ahead). @param {string[]} keys */
  retryAfter(keys) {
    const t = this.now();
    let wait = 0;
    for (const k of keys) {
      const e = this.keys.get(k);
      if (e && e.until > t) wait = Math.max(wait, Math.ceil((e.until - t) / 1000));
    }
    return wait;
  }

  /** @param {string[]} keys */
  fail(keys) {
    const t = this.now();
    for (const k of keys) {
      const e = this.keys.get(k) || { fails: [], until: 0 };
      e.fails = e.fails.filter((x) => t - x < this.windowMs);
      e.fails.push(t);
      if (e.fails.length >= this.max) { e.until = t + this.cooldownMs; e.fails = []; }
      this.keys.set(k, e);
    }
    if (this.keys.size > 10_000) this.prune();
  }

  /** @param {string[]} keys */
  succeed(keys) {
    for (const k of keys) this.keys.delete(k);
  }

  prune() {
    const t = this.now();
    for (const [k, e] of this.keys) if (e.until <= t && e.fails.every((x) => t - x >= this.windowMs)) this.keys.delete(k);
  }
}
