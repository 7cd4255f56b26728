// Single point of control: one session at a time may command motion. The holder keeps the lease with
// heartbeats; it ends on release, logout, disconnect or missed heartbeats; a role the cell file allows
// (`roles.<role>.take_over`) may take it over. The holder outlives a restart of the BFF when the BFF is back
// within the heartbeat timeout of the last heartbeat (`persist` saves it, `resume` reads it back): motion stopped
// when the link dropped, but the operator need not take control again after a quick restart.

/** @typedef {{username: string, role: string, sid: string}} Holder */
/** @typedef {Holder & {since: number, beat: number}} SavedLease */

export class ControlLease {
  /**
   * @param {{timeoutMs?: number, now?: () => number, onChange?: (event: string, h: Holder|null, by?: Holder) => void,
   *   persist?: (saved: SavedLease | null) => void, awake?: () => number}} [o]  persist: called whenever the holder or
   *   its heartbeat changes; awake: a clock (ms) that runs only while this process runs (AwakeClock), for the timeout:
   *   a BFF whose own event loop was stalled (a busy host) did not hear the heartbeats waiting for it, and must not
   *   count that time as the holder's silence
   */
  constructor({ timeoutMs = 2000, now = Date.now, onChange = () => {}, persist = () => {}, awake = now } = {}) {
    this.timeoutMs = timeoutMs;
    this.now = now;
    this.awake = awake;
    this.onChange = onChange;
    this.persist = persist;
    /** beat: wall clock (saved, compared across a restart); heard: the awake clock at that heartbeat (the timeout).
     * @type {(SavedLease & {heard: number, resumedAt?: number}) | null} */
    this.holder = null;
    /** Why the last holder lost control, told to that session when it next heartbeats. @type {{sid: string, reason: string} | null} */
    this.ended = null;
  }

  /**
   * Take back the lease saved by the previous BFF process: kept when this process was started within the heartbeat
   * timeout of the holder's last heartbeat, else ended (and the holder told why on its next heartbeat). The gap is
   * measured to this process's start, not to the end of its start-up: loading takes a second or more on a busy
   * robot PC and is no silence of the holder's. A kept lease gets a full timeout from now for the next heartbeat.
   * @param {SavedLease | null} saved @param {number} [startedAt] when this process started (ms since the epoch)
   * @returns {'resumed' | 'lapsed' | 'none'}
   */
  resume(saved, startedAt = this.now()) {
    if (!saved) return 'none';
    const gap = Math.max(0, startedAt - saved.beat);
    if (gap <= this.timeoutMs) {
      const t = this.now();
      this.holder = { ...strip(saved), since: saved.since, beat: t, heard: this.awake(), resumedAt: t };
      this.#save();
      this.onChange('resumed', strip(saved));
      return 'resumed';
    }
    this.ended = {
      sid: saved.sid,
      reason: `control lapsed while the server restarted (it was back ${(gap / 1000).toFixed(1)} s after the last heartbeat; the limit is ${this.timeoutMs / 1000} s)`,
    };
    this.onChange('lapsed-in-restart', strip(saved));
    this.persist(null);
    return 'lapsed';
  }

  /**
   * The BFF now hears heartbeats (it listens): a resumed holder's timeout starts now, however long the rest of the
   * start-up took after resume().
   */
  listening() {
    if (this.holder?.resumedAt !== undefined) {
      const t = this.now();
      this.holder.beat = t;
      this.holder.heard = this.awake();
      this.holder.resumedAt = t;
      this.#save();
    }
  }

  /** The current holder, after expiring a silent one. */
  current() {
    if (this.holder && this.awake() - this.holder.heard > this.timeoutMs) {
      const h = this.holder;
      this.#end(`the lease expired (no heartbeat reached the server in ${this.timeoutMs / 1000} s)`);
      this.onChange('expired', strip(h));
    }
    return this.holder;
  }

  /** Why this session's control ended, if it was the last holder. @param {{sid: string}} s */
  endedFor(s) {
    return this.ended?.sid === s.sid ? this.ended.reason : null;
  }

  /** @param {string} reason */
  #end(reason) {
    if (this.holder) this.ended = { sid: this.holder.sid, reason };
    this.holder = null;
    this.persist(null);
  }

  #save() {
    const h = this.holder;
    this.persist(h && { ...strip(h), since: h.since, beat: h.beat });
  }

  /** @param {Holder} s */
  isHolder(s) {
    const h = this.current();
    return !!h && h.sid === s.sid;
  }

  /**
   * @param {Holder} s @param {{force?: boolean, mayTakeOver?: boolean}} [o] mayTakeOver: the role may take over
   * @returns {{ok: true} | {ok: false, reason: string, holder: Holder}}
   */
  take(s, { force = false, mayTakeOver = false } = {}) {
    const h = this.current();
    if (h && h.sid !== s.sid) {
      if (!(force && mayTakeOver)) {
        return { ok: false, reason: `control is held by ${h.username} (${h.role})${mayTakeOver ? '; take it over to proceed' : ''}`, holder: strip(h) };
      }
      this.#end(`taken over by ${s.username} (${s.role})`);
      this.onChange('taken-over', strip(h), strip(s));
    }
    const t = this.now();
    const same = h?.sid === s.sid;
    this.holder = { username: s.username, role: s.role, sid: s.sid, since: same ? h.since : t, beat: t, heard: this.awake(), resumedAt: same ? h.resumedAt : undefined };
    this.#save();
    if (!same) this.onChange('taken', strip(s));
    return { ok: true };
  }

  /** @param {Holder} s */
  heartbeat(s) {
    if (!this.isHolder(s)) return false;
    const h = /** @type {NonNullable<typeof this.holder>} */ (this.holder);
    h.beat = this.now();
    h.heard = this.awake();
    this.#save();
    return true;
  }

  /** @param {{sid: string}} s @param {string} [why] */
  release(s, why = 'released') {
    if (this.holder && this.holder.sid === s.sid) {
      const h = this.holder;
      this.#end(RELEASE_REASONS[why] ?? why);
      this.onChange(why, strip(h));
      return true;
    }
    return false;
  }

  /** resumed_at: when this BFF took the lease back from the one before it (a restart). @returns {{username: string, role: string, since: string, resumed_at?: string} | null} */
  describe() {
    const h = this.current();
    if (!h) return null;
    const d = { username: h.username, role: h.role, since: new Date(h.since).toISOString() };
    return h.resumedAt ? { ...d, resumed_at: new Date(h.resumedAt).toISOString() } : d;
  }
}

/** @type {Record<string, string>} */
const RELEASE_REASONS = {
  released: 'control was released',
  'released-on-disconnect': "this session's last live connection closed",
  'released-on-logout': 'the session signed out',
};

/** @param {Holder} h @returns {Holder} */
const strip = (h) => ({ username: h.username, role: h.role, sid: h.sid });
