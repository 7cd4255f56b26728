/**
 * Staleness of live values: every live value shows its age and is marked stale once it is older than
 * the period it is expected to be refreshed in.
 */

import { m } from '$lib/paraglide/messages.js';
import { fmtNumber } from '../core/i18n.js';

/** @param {number | null | undefined} at @param {number} now */
export function ageMs(at, now) {
  return typeof at === 'number' ? Math.max(0, now - at) : null;
}

/**
 * @param {number | null | undefined} at  when the value was last known to hold (ms since the epoch)
 * @param {number} periodMs  how often it is expected to be refreshed
 * @param {number} now
 */
export function isStale(at, periodMs, now) {
  const age = ageMs(at, now);
  return age === null || age > periodMs;
}

/** "just now", "12 s ago", "3 min ago", "2 h ago", "4 d ago". @param {number | null} ms */
export function formatAge(ms) {
  if (ms === null || !Number.isFinite(ms)) return m.shell_age_never();
  const s = Math.floor(ms / 1000);
  if (s < 2) return m.shell_age_just_now();
  if (s < 60) return m.shell_age_s_ago({ n: fmtNumber(s) });
  const min = Math.floor(s / 60);
  if (min < 60) return m.shell_age_min_ago({ n: fmtNumber(min) });
  const h = Math.floor(min / 60);
  if (h < 48) return m.shell_age_h_ago({ n: fmtNumber(h) });
  return m.shell_age_d_ago({ n: fmtNumber(Math.floor(h / 24)) });
}

/**
 * What a live value's age label says.
 * @param {{ at: number | null | undefined, periodMs: number, now: number, live?: boolean }} o
 *   live: an event-driven (latched) value that is current while its subscription is up
 * @returns {{ stale: boolean, text: string }}
 */
export function freshness({ at, periodMs, now, live }) {
  if (live) return { stale: false, text: m.shell_fresh_live() };
  if (at === null || at === undefined) return { stale: true, text: m.shell_fresh_no_data() };
  const stale = live === false || isStale(at, periodMs, now);
  const age = formatAge(ageMs(at, now));
  return { stale, text: stale ? m.shell_fresh_stale({ age }) : m.shell_fresh_updated({ age }) };
}
