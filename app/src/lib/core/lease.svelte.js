/**
 * The control lease, as this session sees it: one session at a time may command motion.
 *
 * HTTP (BFF): GET /api/control -> {holder: {username, role, since} | null, you}; POST take [{force}]
 * -> view or 409 {error, holder}; POST heartbeat -> view or 409 {error, holder}; POST release -> 204.
 * The server drops a lease after 2 s without a heartbeat, so while we hold it we heartbeat every
 * 500 ms; otherwise, while someone shows the lease (watch()), we poll every 1.5 s. A heartbeat gives up after
 * half the timeout: one request that hangs (a stalled connection) must not hold back the next until the lease is gone.
 * In the browser the heartbeats go from a worker (lease-beat.js), so a page busy for a moment keeps its control.
 * Losing the lease (taken over, expired, server unreachable) leaves a notice in `lost` until dismissed
 * or control is taken again. A BFF that restarts within the timeout gives the lease back to its holder
 * (holder.resumed_at): that leaves a notice in `kept`; one that was back too late answers the heartbeat
 * with 409 and `ended` saying so. So after losing control to an unreachable server we go on heartbeating
 * (for `reclaimMs`) to hear which it was.
 */

import { m } from '$lib/paraglide/messages.js';
import { api as defaultApi, resultOf } from './api.js';
import { session } from './session.svelte.js';
import { HeartbeatLoop } from './lease-beat.js';

/** @typedef {import('./api.js').ApiResult} ApiResult */
/** @typedef {import('./lease-beat.js').Beater<ApiResult>} LeaseBeater */

/** @typedef {{ username: string, role: string, since?: string }} LeaseHolder */
/** @typedef {{ reason: string, at: number }} LostNotice */

/** @param {LeaseHolder | null | undefined} h */
export const holderLabel = (h) => (h ? `${h.username} (${h.role})` : m.core_nobody());

export class ControlLease {
  /** Who holds control (null: nobody, as far as we know). @type {LeaseHolder | null} */
  holder = $state(null);
  // Whether this session holds it: a plain field for the logic, mirrored into state for the UI.
  // (Logic must not read the state: inside an effect's teardown Svelte hands out the old value.)
  #you = false;
  #youShown = $state(false);
  /** Whether this session holds control. */
  get you() {
    return this.#youShown;
  }
  set you(v) {
    this.#you = v;
    this.#youShown = v;
  }
  /** Whether the last request reached the server (false: unknown, e.g. offline). */
  reachable = $state(false);
  /** Why we lost control, until dismissed. @type {LostNotice | null} */
  lost = $state(null);
  /** We kept control through something worth telling (a server restart), until dismissed. @type {LostNotice | null} */
  kept = $state(null);

  #watchers = 0;
  /** @type {any} */
  #timer = null;
  #inflight = false;
  #lastOk = 0;
  // The resumed_at we have already told about (or that predates our taking control).
  /** @type {string | undefined} */
  #resumedSeen = undefined;
  // Bumped by take/release/reset so an answer to an older request does not undo a newer one.
  #epoch = 0;
  // Until when we go on heartbeating after losing control to an unreachable server (0: not reclaiming).
  #reclaimUntil = 0;
  // What the beater was started for (epoch and timing), '' while it is stopped.
  #beatKey = '';

  /**
   * @param {object} [o]
   * @param {Pick<typeof defaultApi, 'control' | 'controlTake' | 'controlHeartbeat' | 'controlRelease'>} [o.api]
   * @param {number} [o.heartbeatMs]
   * @param {number} [o.pollMs]
   * @param {number} [o.timeoutMs]  the server's lease timeout
   * @param {number} [o.heartbeatTimeoutMs]  how long one heartbeat may take (default: half the lease timeout)
   * @param {number} [o.reclaimMs]  how long to keep asking an unreachable server whether it kept our control
   * @param {() => number} [o.now]
   * @param {(fn: () => void, ms: number) => any} [o.setTimer]
   * @param {(t: any) => void} [o.clearTimer]
   * @param {() => void} [o.onUnauthorized]  the session ended (401)
   * @param {LeaseBeater | null} [o.beater]  sends the heartbeats (default: from this thread, on setTimer)
   */
  constructor(o = {}) {
    this.api = o.api ?? defaultApi;
    this.heartbeatMs = o.heartbeatMs ?? 500;
    this.pollMs = o.pollMs ?? 1500;
    this.timeoutMs = o.timeoutMs ?? 2000;
    this.heartbeatTimeoutMs = o.heartbeatTimeoutMs ?? this.timeoutMs / 2;
    this.reclaimMs = o.reclaimMs ?? 30_000;
    this.now = o.now ?? Date.now;
    this.setTimer = o.setTimer ?? ((fn, ms) => setTimeout(fn, ms));
    this.clearTimer = o.clearTimer ?? ((t) => clearTimeout(t));
    this.onUnauthorized = o.onUnauthorized ?? (() => {});
    /** @type {LeaseBeater} */
    this.beater = o.beater ?? new HeartbeatLoop({
      send: (ms) => this.api.controlHeartbeat(ms),
      setTimer: this.setTimer,
      clearTimer: this.clearTimer,
      now: this.now,
    });
  }

  /**
   * The cell's lease timeout (GET /api/config control.heartbeat_timeout_s); each heartbeat then gives up after half
   * of it. Anything not a positive number leaves the timeout as it is.
   * @param {unknown} seconds
   */
  configure(seconds) {
    const s = Number(seconds);
    if (!(s > 0)) return;
    this.timeoutMs = s * 1000;
    this.heartbeatTimeoutMs = this.timeoutMs / 2;
  }

  /** Someone shows the lease: keep it fresh. Returns the function that stops watching. */
  watch() {
    this.#watchers++;
    if (this.#watchers === 1 && !this.#you) this.#tick();
    let done = false;
    return () => {
      if (done) return;
      done = true;
      this.#watchers--;
      this.#schedule();
    };
  }

  /** Ask the server who holds control now. */
  async refresh() {
    const epoch = this.#epoch;
    const r = await this.api.control();
    if (epoch !== this.#epoch) return;
    this.#handleRead(r);
  }

  /**
   * Take control (force: take it over from another session; only roles allowed to).
   * Resolves with the view; throws an Error with the server's message when refused or offline.
   * @param {{ force?: boolean }} [o]
   */
  async take(o = {}) {
    const epoch = ++this.#epoch;
    this.#reclaimUntil = 0;
    const r = await this.api.controlTake(o.force ? { force: true } : undefined);
    if (epoch !== this.#epoch) throw new Error(m.core_lease_superseded());
    if (r.kind === 'ok') {
      this.reachable = true;
      this.lost = null;
      this.kept = null;
      this.#lastOk = this.now();
      this.#resumedSeen = r.data?.holder?.resumed_at;
      this.#apply(r.data);
      this.#schedule();
      return r.data;
    }
    if (r.kind === 'offline') {
      this.reachable = false;
      throw new Error(m.core_lease_offline());
    }
    if (r.kind === 'unauthorized') {
      this.onUnauthorized();
      throw new Error(r.error);
    }
    this.reachable = true;
    if (r.data && 'holder' in r.data) this.holder = r.data.holder ?? null;
    throw new Error(r.error || m.core_lease_not_taken());
  }

  /** Give control back. Throws only when the server answers with an error other than "offline". */
  async release() {
    const epoch = ++this.#epoch;
    this.#reclaimUntil = 0;
    const wasYou = this.#you;
    // Stop heartbeating at once: even if the release does not reach the server, the lease ends in 2 s.
    this.you = false;
    this.kept = null;
    if (wasYou) this.holder = null;
    this.#schedule();
    const r = await this.api.controlRelease();
    if (epoch !== this.#epoch) return;
    if (r.kind === 'unauthorized') this.onUnauthorized();
    else if (r.kind === 'error') throw new Error(r.error || m.core_lease_release_failed());
    this.reachable = r.kind !== 'offline';
    if (this.#watchers > 0) this.#tick();
  }

  /**
   * Release with a notice saying why (e.g. the app went to the background).
   * @param {string} reason
   */
  async releaseBecause(reason) {
    if (!this.#you) return;
    this.lost = { reason, at: this.now() };
    try {
      await this.release();
    } catch {
      /* the lease expires on its own */
    }
  }

  dismissLost() {
    this.lost = null;
  }

  dismissKept() {
    this.kept = null;
  }

  /** Forget everything and stop all timers (logout). Does not call the server. */
  reset() {
    this.#epoch++;
    this.#reclaimUntil = 0;
    if (this.#timer !== null) this.clearTimer(this.#timer);
    this.#timer = null;
    this.#stopBeating();
    this.#watchers = 0;
    this.holder = null;
    this.you = false;
    this.reachable = false;
    this.lost = null;
    this.kept = null;
  }

  /** @param {{ holder?: LeaseHolder | null, you?: boolean } | null} view */
  #apply(view) {
    const wasYou = this.#you;
    this.holder = view?.holder ?? null;
    this.you = view?.you === true;
    if (this.#you && !wasYou) this.#lastOk = this.now();
  }

  /** @param {string} reason */
  #lose(reason) {
    this.you = false;
    this.kept = null;
    this.lost = { reason, at: this.now() };
  }

  /** An answer to GET /api/control. @param {import('./api.js').ApiResult} r */
  #handleRead(r) {
    if (r.kind === 'ok') {
      this.reachable = true;
      const wasYou = this.#you;
      this.#apply(r.data);
      if (wasYou && !this.#you) this.#lose(this.holder ? m.core_lease_taken_over({ holder: holderLabel(this.holder) }) : m.core_lease_expired());
    } else if (r.kind === 'offline') {
      this.reachable = false;
    } else if (r.kind === 'unauthorized') {
      this.onUnauthorized();
    }
  }

  #reclaiming() {
    return this.#reclaimUntil > 0 && this.now() <= this.#reclaimUntil;
  }

  /** Heartbeats go while we hold control or ask whether we still do; a take, a release or a new timeout restarts them. */
  #syncBeat() {
    if (!(this.#you || this.#reclaiming())) {
      this.#stopBeating();
      return;
    }
    const epoch = this.#epoch;
    const key = `${epoch}/${this.heartbeatMs}/${this.timeoutMs}`;
    if (key === this.#beatKey) return;
    this.#beatKey = key;
    // A page that has not taken an answer for a whole lease timeout is hung: its heartbeats stop (lease-beat.js).
    const o = { intervalMs: this.heartbeatMs, timeoutMs: this.heartbeatTimeoutMs, stallMs: this.timeoutMs };
    this.beater.start(o, (r) => {
      this.#onBeat(r, epoch);
      this.#schedule();
    });
  }

  #stopBeating() {
    if (!this.#beatKey) return;
    this.#beatKey = '';
    this.beater.stop();
  }

  /** A heartbeat's answer. @param {ApiResult} r @param {number} epoch when it was started */
  #onBeat(r, epoch) {
    if (epoch !== this.#epoch || !(this.#you || this.#reclaiming())) return;
    this.beater.ack();
    const reclaiming = !this.#you;
    if (r.kind === 'ok') {
      this.reachable = true;
      this.#lastOk = this.now();
      this.#reclaimUntil = 0;
      this.#apply(r.data);
      if (!this.#you) {
        if (!reclaiming) this.#lose(m.core_lease_not_holder());
        return;
      }
      if (reclaiming) this.lost = null;
      const resumed = r.data?.holder?.resumed_at;
      if (resumed && resumed !== this.#resumedSeen) {
        this.#resumedSeen = resumed;
        this.kept = { reason: m.core_lease_kept(), at: this.now() };
      }
      return;
    }
    if (r.kind === 'unauthorized') {
      this.#reclaimUntil = 0;
      this.#lose(m.core_lease_session_ended());
      this.onUnauthorized();
      return;
    }
    if (r.kind === 'offline') {
      this.reachable = false;
      // The server drops a silent holder after its timeout, unless it restarts in time and gives control back:
      // lose it now, and keep asking for a while.
      if (!reclaiming && this.now() - this.#lastOk > this.timeoutMs) {
        this.#lose(m.core_lease_unreachable());
        this.#reclaimUntil = this.now() + this.reclaimMs;
      }
      return;
    }
    this.reachable = true;
    this.#reclaimUntil = 0;
    if (r.status === 409) {
      const h = r.data?.holder ?? null;
      this.holder = h;
      // ended: the server's own account, when it has one (e.g. control lapsed while it restarted)
      const ended = typeof r.data?.ended === 'string' ? r.data.ended : null;
      this.#lose(ended ?? (h ? m.core_lease_taken_over({ holder: holderLabel(h) }) : m.core_lease_expired_heartbeat()));
    }
  }

  async #tick() {
    if (this.#timer !== null) this.clearTimer(this.#timer);
    this.#timer = null;
    if (this.#inflight) return;
    this.#inflight = true;
    try {
      if (!(this.#you || this.#reclaiming()) && this.#watchers > 0) await this.refresh();
    } catch {
      /* the API client does not throw; keep the loop alive anyway */
    } finally {
      this.#inflight = false;
      this.#schedule();
    }
  }

  #schedule() {
    if (this.#reclaimUntil > 0 && !this.#reclaiming()) this.#reclaimUntil = 0;
    this.#syncBeat();
    if (this.#inflight) return; // #tick schedules when its request is answered
    if (this.#timer !== null) this.clearTimer(this.#timer);
    this.#timer = null;
    const beating = this.#you || this.#reclaimUntil > 0;
    if (!beating && this.#watchers > 0) this.#timer = this.setTimer(() => this.#tick(), this.pollMs);
  }
}

/**
 * Heartbeats from a dedicated worker (lease-worker.js), their answers read here; null where the browser has no
 * module workers (the lease then beats from the page). A worker that fails to load hands over to the page.
 * @returns {LeaseBeater | null}
 */
export function workerBeater() {
  if (typeof Worker === 'undefined') return null;
  /** @type {Worker} */
  let worker;
  try {
    worker = new Worker(new URL('./lease-worker.js', import.meta.url), { type: 'module' });
  } catch {
    return null;
  }
  let gen = 0;
  /** @type {{ o: import('./lease-beat.js').BeatOptions, onAnswer: (r: ApiResult) => void } | null} */
  let current = null;
  /** @type {HeartbeatLoop<ApiResult> | null} */
  let fallback = null;
  worker.onmessage = async (e) => {
    if (e.data?.gen !== gen || !current) return;
    const { onAnswer } = current;
    const r = await resultOf(e.data.answer);
    if (e.data.gen === gen) onAnswer(r);
  };
  worker.onerror = () => {
    if (fallback) return;
    fallback = new HeartbeatLoop({ send: (ms) => defaultApi.controlHeartbeat(ms) });
    if (current) fallback.start(current.o, current.onAnswer);
  };
  return {
    start(o, onAnswer) {
      current = { o, onAnswer };
      if (fallback) fallback.start(o, onAnswer);
      else worker.postMessage({ start: o, gen: ++gen });
    },
    stop() {
      current = null;
      gen++;
      if (fallback) fallback.stop();
      else worker.postMessage({ stop: true });
    },
    ack() {
      if (!fallback) worker.postMessage({ ack: true });
    },
  };
}

/** The app's lease view (the shell resets it on logout; lease bars watch it). */
export const lease = new ControlLease({ onUnauthorized: () => session.expire(), beater: workerBeater() });
