// Whether a child that is still running but no longer answers (a blocked event loop, a deadlock) must be killed,
// so that the supervisor restarts it as it restarts one that died. Pure: the clock is injected, the probing (an
// HTTP health check) is the caller's.
//
// A process is judged only once it has answered since it started: start-up (which may take long on a busy robot
// PC) is not a hang. After that, `graceMs` without an answer is one.

/** @typedef {{graceMs?: number, now?: () => number}} LivenessOptions */

export const DEFAULT_GRACE_MS = 30_000;

export class Liveness {
  /** @param {LivenessOptions} [opts] */
  constructor(opts = {}) {
    this.graceMs = opts.graceMs ?? DEFAULT_GRACE_MS;
    this.now = opts.now ?? Date.now;
    /** @type {number | null} when it last answered; null until its first answer since it started */
    this.lastAnswer = null;
  }

  /** A new process of the child started: not judged until it answers. */
  started() {
    this.lastAnswer = null;
  }

  /** The probe got an answer. */
  answered() {
    this.lastAnswer = this.now();
  }

  /** ms since the last answer (0 while not judged yet). */
  silentMs() {
    return this.lastAnswer === null ? 0 : this.now() - this.lastAnswer;
  }

  /** It answered once and has not answered for `graceMs`: kill it. */
  hung() {
    return this.lastAnswer !== null && this.silentMs() >= this.graceMs;
  }
}

/**
 * The grace period from the environment (`LIVENESS_TIMEOUT_S`, seconds; 0 turns the check off).
 * @param {NodeJS.ProcessEnv} env @returns {number | null} ms, or null when off
 */
export function graceFromEnv(env) {
  const raw = env.LIVENESS_TIMEOUT_S;
  if (raw === undefined || raw === '') return DEFAULT_GRACE_MS;
  const s = Number(raw);
  if (!Number.isFinite(s) || s < 0) throw new Error(`LIVENESS_TIMEOUT_S must be a number of seconds (0: off), not ${JSON.stringify(raw)}`);
  return s === 0 ? null : s * 1000;
}
