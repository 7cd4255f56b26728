// A clock that runs only while this process runs. A tick every `tickMs` adds the time since the last one, at most
// `maxStepMs`: when the event loop was stalled (a busy host, a long synchronous step) the stall beyond that is not
// counted. The control lease measures its heartbeat timeout on it, so that heartbeats that were waiting in the
// socket while the BFF could not run are not taken for the holder's silence.

export class AwakeClock {
  /** @param {{tickMs?: number, maxStepMs?: number, now?: () => number, timers?: boolean}} [o] timers: tick on its own */
  constructor({ tickMs = 100, maxStepMs = 250, now = () => performance.now(), timers = true } = {}) {
    this.maxStepMs = maxStepMs;
    this.clock = now;
    this.last = now();
    this.elapsed = 0;
    /** @type {ReturnType<typeof setInterval> | null} */
    this.timer = timers ? setInterval(() => this.tick(), tickMs) : null;
    this.timer?.unref();
  }

  tick() {
    const t = this.clock();
    this.elapsed += Math.min(Math.max(0, t - this.last), this.maxStepMs);
    this.last = t;
  }

  /** Milliseconds this process was awake (since the clock was made). */
  now() {
    this.tick();
    return this.elapsed;
  }

  stop() {
    if (this.timer) clearInterval(this.timer);
    this.timer = null;
  }
}
