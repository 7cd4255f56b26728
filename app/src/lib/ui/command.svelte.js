/**
 * Feedback for one command control: idle -> pending -> done | failed (with the backend's message).
 * A second press while pending is ignored (commands never pile up); "done" fades back to idle.
 */

import { m } from '$lib/paraglide/messages.js';

/** @typedef {'idle' | 'pending' | 'done' | 'failed'} CommandStatus */

export class Command {
  /** @type {CommandStatus} */
  status = $state('idle');
  /** The failure message, or a short result text. */
  message = $state('');

  /** @type {any} */
  #timer = null;

  /**
   * @param {object} [o]
   * @param {number} [o.doneMs]  how long "done" stays before going back to idle (0: stays)
   * @param {(fn: () => void, ms: number) => any} [o.setTimer]
   * @param {(t: any) => void} [o.clearTimer]
   */
  constructor(o = {}) {
    this.doneMs = o.doneMs ?? 5000;
    this.setTimer = o.setTimer ?? ((fn, ms) => setTimeout(fn, ms));
    this.clearTimer = o.clearTimer ?? ((t) => clearTimeout(t));
  }

  get pending() {
    return this.status === 'pending';
  }

  /**
   * Run the command. Resolves with its result, or undefined when it failed or was already running;
   * never rejects (the failure is in `status`/`message`).
   * @template T
   * @param {() => Promise<T> | T} fn
   * @returns {Promise<T | undefined>}
   */
  async run(fn) {
    if (this.status === 'pending') return undefined;
    this.#clear();
    this.status = 'pending';
    this.message = '';
    try {
      const r = await fn();
      this.status = 'done';
      this.message = '';
      if (this.doneMs > 0) {
        this.#timer = this.setTimer(() => {
          this.#timer = null;
          if (this.status === 'done') this.status = 'idle';
        }, this.doneMs);
      }
      return r;
    } catch (e) {
      this.status = 'failed';
      this.message = errorMessage(e);
      return undefined;
    }
  }

  dismiss() {
    this.#clear();
    if (this.status !== 'pending') {
      this.status = 'idle';
      this.message = '';
    }
  }

  #clear() {
    if (this.#timer !== null) this.clearTimer(this.#timer);
    this.#timer = null;
  }
}

/** @param {unknown} e */
export function errorMessage(e) {
  if (e instanceof Error) return e.message || e.name;
  if (typeof e === 'string' && e) return e;
  return m.shell_cmd_error();
}

/**
 * For std_srvs/Trigger-like answers ({success, message}): a refusal becomes a failure with the
 * backend's message.
 * @template T
 * @param {T} values
 * @returns {T}
 */
export function expectSuccess(values) {
  const v = /** @type {any} */ (values);
  if (v && v.success === false) throw new Error(v.message || m.shell_cmd_refused());
  return values;
}
