// Single point of control: one session at a time may command motion. The holder keeps the lease with
// heartbeats; it ends on release, logout, disconnect or missed heartbeats; a role the cell file allows
// (`roles.<role>.take_over`) may take it over.

/** @typedef {{username: string, role: string, sid: string}} Holder */

export class ControlLease {
  /** @param {{timeoutMs?: number, now?: () => number, onChange?: (event: string, h: Holder|null, by?: Holder) => void}} [o] */
  constructor({ timeoutMs = 2000, now = Date.now, onChange = () => {} } = {}) {
    this.timeoutMs = timeoutMs;
    this.now = now;
    this.onChange = onChange;
    /** @type {(Holder & {since: number, beat: number}) | null} */
    this.holder = null;
  }

  /** The current holder, after expiring a silent one. */
  current() {
    if (this.holder && this.now() - this.holder.beat > this.timeoutMs) {
      const h = this.holder;
      this.holder = null;
      this.onChange('expired', h);
    }
    return this.holder;
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
      this.onChange('taken-over', strip(h), strip(s));
    }
    const t = this.now();
    this.holder = { username: s.username, role: s.role, sid: s.sid, since: h?.sid === s.sid ? h.since : t, beat: t };
    if (!h || h.sid !== s.sid) this.onChange('taken', strip(s));
    return { ok: true };
  }

  /** @param {Holder} s */
  heartbeat(s) {
    if (!this.isHolder(s)) return false;
    /** @type {any} */ (this.holder).beat = this.now();
    return true;
  }

  /** @param {{sid: string}} s @param {string} [why] */
  release(s, why = 'released') {
    if (this.holder && this.holder.sid === s.sid) {
      const h = this.holder;
      this.holder = null;
      this.onChange(why, strip(h));
      return true;
    }
    return false;
  }

  /** @returns {{username: string, role: string, since: string} | null} */
  describe() {
    const h = this.current();
    return h ? { username: h.username, role: h.role, since: new Date(h.since).toISOString() } : null;
  }
}

/** @param {Holder} h @returns {Holder} */
const strip = (h) => ({ username: h.username, role: h.role, sid: h.sid });
