/**
 * The audit log view's plain logic: the query (filters and paging) of GET /api/audit, the page's position
 * ("26–50 of 230"), and how an entry's outcome looks. The log is newest first (bff/src/core/audit/audit-log.js);
 * filters match exactly (user, op, outcome).
 */
import { m } from '$lib/paraglide/messages.js';
import { fmtNumber, fmtDateTime } from '$lib/core/i18n.js';
import { request } from '../../core/api.js';

/** Entries per page. */
export const PAGE_SIZE = 25;

export const OUTCOMES = Object.freeze(['ok', 'denied', 'failed']);

/** Operations the BFF records, offered as suggestions for the operation filter (any other text works too). */
export const KNOWN_OPS = Object.freeze([
  'login', 'logout', 'control.taken', 'control.taken-over', 'control.released', 'control.released-on-disconnect',
  'control.released-on-logout', 'control.expired',
  'ros.publish', 'ros.call_service', 'ros.advertise', 'ros.advertise_service', 'ros.subscribe',
  'database.replace', 'database.restore',
]);

/**
 * @typedef {{ user: string, op: string, outcome: string }} AuditFilters
 * @typedef {{ time?: string, user: string | null, role: string | null, ip: string | null, op: string, target?: string,
 *   outcome: string, detail?: string }} AuditEntry
 */

/** @type {AuditFilters} */
export const NO_FILTERS = Object.freeze({ user: '', op: '', outcome: '' });

/**
 * The query string of GET /api/audit for filters and an offset (empty filters are left out).
 * @param {AuditFilters} f @param {number} offset @param {number} [limit]
 */
export function auditQuery(f, offset, limit = PAGE_SIZE) {
  const p = new URLSearchParams();
  const user = f.user.trim(), op = f.op.trim();
  if (user) p.set('user', user);
  if (op) p.set('op', op);
  if (f.outcome) p.set('outcome', f.outcome);
  p.set('offset', String(Math.max(0, Math.floor(offset) || 0)));
  p.set('limit', String(limit));
  return p.toString();
}

/** @param {AuditFilters} f @param {number} offset @param {number} [limit] */
export const fetchAudit = (f, offset, limit = PAGE_SIZE) => request('GET', `/api/audit?${auditQuery(f, offset, limit)}`);

/** A count as the position line shows it. @param {number} n */
export const count = (n) => fmtNumber(n, { useGrouping: false });

/**
 * Where a page sits in the log.
 * @param {number} total @param {number} offset @param {number} shown  entries on this page
 * @param {number} [limit]
 */
export function pageInfo(total, offset, shown, limit = PAGE_SIZE) {
  const from = shown > 0 ? offset + 1 : 0;
  const to = offset + shown;
  return {
    from,
    to,
    total,
    hasNewer: offset > 0,
    hasOlder: to < total,
    newerOffset: Math.max(0, offset - limit),
    olderOffset: offset + limit,
    // (counts without grouping: the position reads "26–50 of 1230" in every language)
    text: total === 0 ? m.system_audit_no_entries()
      : shown === 0 ? m.system_audit_past_end({ total: count(total) })
      : m.system_audit_position({ from: count(from), to: count(to), total: count(total) }),
  };
}

/** Whether any filter is set. @param {AuditFilters} f */
export const filtered = (f) => !!(f.user.trim() || f.op.trim() || f.outcome);

/** An outcome as colour and label (in the user's language). @param {string} o */
export function outcomeView(o) {
  if (o === 'ok') return { tone: 'ok', label: m.system_outcome_ok() };
  if (o === 'denied') return { tone: 'warn', label: m.system_outcome_denied() };
  if (o === 'failed') return { tone: 'danger', label: m.system_outcome_failed() };
  return { tone: 'neutral', label: o || m.system_outcome_unknown() };
}

/** An entry's date and time in the user's locale, with seconds ("22 Nov 2026, 14:03:21" in Spanish). @param {string | undefined} iso */
export function auditTime(iso) {
  if (!iso) return '—';
  const d = new Date(iso);
  if (Number.isNaN(d.getTime())) return iso;
  return fmtDateTime(d);
}
