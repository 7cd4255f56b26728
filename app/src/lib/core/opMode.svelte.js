/**
 * Live operation mode of the cell, from the topic named in /api/config (cell_msgs/OperationMode:
 * string mode, string source, time stamp). One subscription for the whole app (the shell's).
 *
 * The topic is latched and only published on change, so the value is fresh exactly while the link is
 * up. `mode` is the live value (null while ROS is unreachable: the shell badge never shows a stale
 * mode); `last` keeps the last value seen and the last moment it was known to hold, for pages that
 * show it marked stale with its age.
 */

import { m } from '$lib/paraglide/messages.js';

/** Badge colour per known mode; unknown modes fall back to neutral. */
export const MODE_TONES = /** @type {Record<string, string>} */ ({
  idle: 'neutral',
  running: 'ok',
  paused: 'warn',
  alarm: 'danger',
  programming: 'info',
  manual: 'accent',
});

/** @param {string | null | undefined} mode */
export function modeTone(mode) {
  return (mode && MODE_TONES[mode]) || 'neutral';
}

/** @param {string | null | undefined} mode */
export function modeLabel(mode) {
  switch (mode) {
    case 'idle': return m.core_mode_idle();
    case 'running': return m.core_mode_running();
    case 'paused': return m.core_mode_paused();
    case 'alarm': return m.core_mode_alarm();
    case 'programming': return m.core_mode_programming();
    case 'manual': return m.core_mode_manual();
    default: return mode ? mode : '—';
  }
}

/** @typedef {{ mode: string, source: string | null, at: number }} KnownMode */

export class OpMode {
  /** @type {string | null} */
  mode = $state(null);
  /** @type {string | null} */
  source = $state(null);
  /** The last mode seen and when it was last known to hold. @type {KnownMode | null} */
  last = $state(null);

  /** @param {() => number} [now] */
  constructor(now = Date.now) {
    this.now = now;
  }

  /** @param {any} msg */
  update(msg) {
    this.mode = typeof msg?.mode === 'string' && msg.mode ? msg.mode : null;
    this.source = typeof msg?.source === 'string' ? msg.source : null;
    this.last = this.mode ? { mode: this.mode, source: this.source, at: this.now() } : this.last;
  }

  /** The link is down: the live value goes, the last one stays with the moment it was lost. */
  reset() {
    if (this.mode) this.last = { mode: this.mode, source: this.source, at: this.now() };
    this.mode = null;
    this.source = null;
  }

  /**
   * @param {{ subscribe: (t: string, type: string, cb: (m: any) => void, o?: any) => () => void }} conn
   * @param {{ topic: string, type: string } | undefined} spec
   * @returns {() => void}
   */
  follow(conn, spec) {
    if (!spec?.topic) return () => {};
    return conn.subscribe(spec.topic, spec.type || 'cell_msgs/OperationMode', (m) => this.update(m));
  }
}

export const opMode = new OpMode();
