/**
 * Live operation mode of the cell, from the topic named in /api/config (cell_msgs/OperationMode:
 * string mode, string source, time stamp). One subscription for the whole app.
 */

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
  return mode ? mode : '—';
}

export class OpMode {
  /** @type {string | null} */
  mode = $state(null);
  /** @type {string | null} */
  source = $state(null);

  /** @param {any} msg */
  update(msg) {
    this.mode = typeof msg?.mode === 'string' && msg.mode ? msg.mode : null;
    this.source = typeof msg?.source === 'string' ? msg.source : null;
  }

  reset() {
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
