/**
 * The control lease's heartbeat, sent on its own cadence: a request, its answer, `intervalMs`, the next request.
 *
 * In the browser it runs in a dedicated worker (lease-worker.js): the page's main thread stalls for a second or two
 * while a page mounts, a camera starts or a slow tablet lays out, and a heartbeat waiting on it would let the lease
 * expire while its holder is looking at the page. The worker is not held up by the page; it goes when the page goes
 * (closed, reloaded), and it stops beating when the page has not taken an answer for `stallMs` (`ack`; the lease
 * gives it the lease timeout), so a page that hangs for good loses control as one that is closed does. The jog's own heartbeat (hold-to-run) stays on the
 * page: a stalled page stops a jog within the driver's 0.2 s whatever the lease does.
 */

/** @typedef {{ intervalMs: number, timeoutMs: number, stallMs?: number }} BeatOptions */
/**
 * @template R
 * @typedef {{ start(o: BeatOptions, onAnswer: (answer: R) => void): void, stop(): void, ack(): void }} Beater
 */

/** @template R */
export class HeartbeatLoop {
  /** @type {any} */
  #timer = null;
  #gen = 0;
  #lastAck = 0;
  /** @type {BeatOptions} */
  #o = { intervalMs: 500, timeoutMs: 1000 };
  /** @type {(answer: R) => void} */
  #onAnswer = () => {};

  /**
   * @param {object} o
   * @param {(timeoutMs: number) => Promise<R>} o.send  one heartbeat request
   * @param {(fn: () => void, ms: number) => any} [o.setTimer]
   * @param {(t: any) => void} [o.clearTimer]
   * @param {() => number} [o.now]
   */
  constructor(o) {
    this.send = o.send;
    this.setTimer = o.setTimer ?? ((fn, ms) => setTimeout(fn, ms));
    this.clearTimer = o.clearTimer ?? ((t) => clearTimeout(t));
    this.now = o.now ?? Date.now;
  }

  /** Beat every `intervalMs` (the first after one interval) until stopped; a new start replaces the old one. */
  /** @param {BeatOptions} o @param {(answer: R) => void} onAnswer */
  start(o, onAnswer) {
    this.stop();
    this.#o = o;
    this.#onAnswer = onAnswer;
    this.#lastAck = this.now();
    this.#next(this.#gen);
  }

  stop() {
    this.#gen++;
    if (this.#timer !== null) this.clearTimer(this.#timer);
    this.#timer = null;
  }

  /** The page took an answer: it is alive. */
  ack() {
    this.#lastAck = this.now();
  }

  /** Whether the page has gone quiet for longer than it may. */
  get stalled() {
    const { stallMs = 0 } = this.#o;
    return stallMs > 0 && this.now() - this.#lastAck > stallMs;
  }

  /** @param {number} gen */
  #next(gen) {
    this.#timer = this.setTimer(() => this.#beat(gen), this.#o.intervalMs);
  }

  /** @param {number} gen */
  async #beat(gen) {
    this.#timer = null;
    if (gen !== this.#gen) return;
    if (!this.stalled) {
      const answer = await this.send(this.#o.timeoutMs);
      if (gen !== this.#gen) return;
      this.#onAnswer(answer);
      if (gen !== this.#gen) return; // the answer stopped or restarted the loop
    }
    this.#next(gen);
  }
}
