// When to restart a child of the stack (scripts/stack.js) that died, and when to stop trying. Pure: the clock
// is injected, nothing here spawns or waits.
//
// - Back-off: the first restart is immediate (a child that ran and died once is most likely a one-off, and every
//   second it is away counts: the BFF must be back within the control lease's heartbeat timeout for the holder to
//   keep control), the second waits `minDelayMs`, each further one twice as long, up to `maxDelayMs`.
// - A child that ran for `stableMs` before it died starts over with an immediate restart.
// - A crash loop: `maxCrashes` crashes within `windowMs` (the last one included). Then restarting is pointless
//   (a port taken, a broken install...): the supervisor gives up and exits non-zero, so whatever supervises
//   it (systemd's Restart=on-failure) takes over with its own, slower, back-off.

export const DEFAULTS = Object.freeze({
  minDelayMs: 500,
  maxDelayMs: 10_000,
  stableMs: 30_000,
  maxCrashes: 5,
  windowMs: 60_000,
});

/**
 * @typedef {object} PolicyOptions
 * @property {number} [minDelayMs]
 * @property {number} [maxDelayMs]
 * @property {number} [stableMs]
 * @property {number} [maxCrashes]
 * @property {number} [windowMs]
 * @property {() => number} [now]  ms; Date.now by default
 */

/**
 * @typedef {object} Decision
 * @property {boolean} giveUp  a crash loop: do not restart
 * @property {number} delayMs  how long to wait before the restart (0 when giving up)
 * @property {number} crashes  crashes within the window, this one included
 * @property {number} maxCrashes
 * @property {number} windowMs
 */

export class RestartPolicy {
  /** @param {PolicyOptions} [opts] */
  constructor(opts = {}) {
    const o = { ...DEFAULTS, ...Object.fromEntries(Object.entries(opts).filter(([, v]) => v !== undefined)) };
    this.minDelayMs = o.minDelayMs;
    this.maxDelayMs = o.maxDelayMs;
    this.stableMs = o.stableMs;
    this.maxCrashes = o.maxCrashes;
    this.windowMs = o.windowMs;
    this.now = opts.now ?? Date.now;
    /** @type {number[]} times of the crashes still within the window */
    this.crashTimes = [];
    /** restarts since the child last ran stably (the back-off exponent) */
    this.attempt = 0;
    /** @type {number | null} */
    this.startedAt = null;
  }

  /** The child was (re)started now. */
  started() {
    this.startedAt = this.now();
  }

  /**
   * The child died without being asked to: restart it after `delayMs`, or give up.
   * @returns {Decision}
   */
  crashed() {
    const t = this.now();
    if (this.startedAt !== null && t - this.startedAt >= this.stableMs) this.attempt = 0;
    this.startedAt = null;
    this.crashTimes = this.crashTimes.filter((c) => t - c < this.windowMs);
    this.crashTimes.push(t);
    const crashes = this.crashTimes.length;
    const base = { crashes, maxCrashes: this.maxCrashes, windowMs: this.windowMs };
    if (crashes >= this.maxCrashes) return { giveUp: true, delayMs: 0, ...base };
    const delayMs = this.attempt === 0 ? 0 : Math.min(this.maxDelayMs, this.minDelayMs * 2 ** (this.attempt - 1));
    this.attempt++;
    return { giveUp: false, delayMs, ...base };
  }
}

/** "0.5 s", "10 s": a delay as the log shows it. @param {number} ms */
export const seconds = (ms) => `${Math.round(ms / 100) / 10} s`;

/** "at once", "in 0.5 s": a restart delay as the log shows it. @param {number} ms */
export const restartDelay = (ms) => (ms === 0 ? 'at once' : `in ${seconds(ms)}`);
