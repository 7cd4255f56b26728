/**
 * Run `task` now and then every `ms`, never overlapping; returns a stop function.
 * @param {() => Promise<unknown> | unknown} task
 * @param {number} ms
 * @returns {() => void}
 */
export function poll(task, ms) {
  let stopped = false;
  /** @type {any} */
  let timer = null;
  const tick = async () => {
    try {
      await task();
    } finally {
      if (!stopped) timer = setTimeout(tick, ms);
    }
  };
  tick();
  return () => {
    stopped = true;
    if (timer) clearTimeout(timer);
  };
}
