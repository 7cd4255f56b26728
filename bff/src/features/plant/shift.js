// Shift statistics of one cell, from what the plant view heard of it: cycles completed in the last hour, and the
// share of the shift (the last 8 h, or since the view first heard of the cell) it spent in operation mode "running".
// Offline time counts as not running. Plain data in, so it is tested without a broker; the view keeps it in memory
// (a restarted BFF starts counting again).

const HOUR_MS = 3600_000;

export class ShiftStats {
  /** @param {{shiftMs?: number}} [o] */
  constructor({ shiftMs = 8 * HOUR_MS } = {}) {
    this.shiftMs = shiftMs;
    /** @type {{t: number, running: boolean}[]} mode changes, oldest first (one before the shift's start kept) */
    this.modes = [];
    /** @type {{t: number, n: number}[]} cycles completed, by when they were reported */
    this.cycles = [];
    /** @type {number | null} */
    this.lastCycles = null;
  }

  /**
   * What the cell reports now.
   * @param {number} t @param {{online: boolean, mode: unknown, cycles: unknown}} s
   */
  observe(t, { online, mode, cycles }) {
    const running = online && mode === 'running';
    if (!this.modes.length || this.modes[this.modes.length - 1].running !== running) this.modes.push({ t, running });
    if (typeof cycles === 'number') {
      // The count is per run: a new run starts again at 0, and what it counts from there is new.
      const done = this.lastCycles !== null && cycles >= this.lastCycles ? cycles - this.lastCycles : this.lastCycles === null ? 0 : cycles;
      if (done > 0) this.cycles.push({ t, n: done });
      this.lastCycles = cycles;
    }
    this.prune(t);
  }

  /** @param {number} now */
  prune(now) {
    while (this.cycles.length && this.cycles[0].t <= now - HOUR_MS) this.cycles.shift();
    while (this.modes.length > 1 && this.modes[1].t <= now - this.shiftMs) this.modes.shift();
  }

  /** @param {number} now @returns {{cycles_last_hour: number, running_share: number | null, observed_s: number}} */
  stats(now) {
    this.prune(now);
    const start = this.modes.length ? Math.max(this.modes[0].t, now - this.shiftMs) : now;
    let running = 0;
    this.modes.forEach((m, i) => {
      const from = Math.max(m.t, start);
      const to = i + 1 < this.modes.length ? this.modes[i + 1].t : now;
      if (m.running && to > from) running += to - from;
    });
    const observed = now - start;
    return {
      cycles_last_hour: this.cycles.reduce((s, c) => s + c.n, 0),
      running_share: observed > 0 ? running / observed : null,
      observed_s: observed / 1000,
    };
  }
}
