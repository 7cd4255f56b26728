/**
 * A ticking "now" for ages and staleness. Reading `clock.now` inside an effect or a template
 * re-runs it every tick; the interval only runs while something reads it.
 */
import { createSubscriber } from 'svelte/reactivity';

export class Clock {
  #subscribe;

  /** @param {number} [intervalMs] @param {() => number} [now] */
  constructor(intervalMs = 1000, now = Date.now) {
    this.read = now;
    this.#subscribe = createSubscriber((update) => {
      const id = setInterval(update, intervalMs);
      return () => clearInterval(id);
    });
  }

  get now() {
    this.#subscribe();
    return this.read();
  }
}

export const clock = new Clock();
