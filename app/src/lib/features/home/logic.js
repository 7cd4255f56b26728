/**
 * Home's plain logic: which operation mode to show, and how fresh it is.
 * The mode topic is latched and published on change only, so a received mode is current exactly while
 * the link is up; when it is not, Home shows the last known one (in memory, else from IndexedDB)
 * marked stale with its age.
 */

/** @typedef {{ mode: string, source: string | null, at: number }} KnownMode */

/**
 * @param {object} o
 * @param {string | null} o.live  the live mode (null while ROS is unreachable or before the first message)
 * @param {string | null} [o.liveSource]
 * @param {KnownMode | null | undefined} o.last  the last mode seen in this app run
 * @param {KnownMode | null | undefined} o.saved  the last mode saved in IndexedDB (earlier runs)
 * @returns {{ mode: string | null, source: string | null, live: boolean, at: number | null, from: 'live' | 'memory' | 'saved' | 'none' }}
 */
export function modeView({ live, liveSource = null, last, saved }) {
  if (live) return { mode: live, source: liveSource, live: true, at: null, from: 'live' };
  const known = [last, saved].filter(isKnownMode).sort((a, b) => b.at - a.at)[0];
  if (known) return { mode: known.mode, source: known.source, live: false, at: known.at, from: known === last ? 'memory' : 'saved' };
  return { mode: null, source: null, live: false, at: null, from: 'none' };
}

/** @param {any} v @returns {v is KnownMode} */
export function isKnownMode(v) {
  return !!v && typeof v.mode === 'string' && v.mode !== '' && typeof v.at === 'number';
}

/**
 * Why Home is not showing live data, if it is not.
 * @param {{ offline: boolean, conn: 'connecting' | 'connected' | 'disconnected', downSince: number | null }} o
 * @returns {'offline' | 'disconnected' | null}
 */
export function notLiveBecause({ offline, conn, downSince }) {
  if (offline) return 'offline';
  if (conn !== 'connected' && (conn === 'disconnected' || downSince !== null)) return 'disconnected';
  return null;
}
