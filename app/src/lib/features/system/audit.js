/**
 * The audit log view's plain logic: the query (filters and paging) of GET /api/audit, the page's position
 * ("26–50 of 230"), and how an entry's outcome looks. The log is newest first (bff/src/core/audit/audit-log.js);
 * filters match exactly (user, op, outcome).
 */
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
    text: total === 0 ? 'No entries' : shown === 0 ? `Past the end (${total} entries)` : `${from}–${to} of ${total}, newest first`,
  };
}

/** Whether any filter is set. @param {AuditFilters} f */
export const filtered = (f) => !!(f.user.trim() || f.op.trim() || f.outcome);

/** An outcome as colour and label. @param {string} o */
export function outcomeView(o) {
  if (o === 'ok') return { tone: 'ok', label: 'OK' };
  if (o === 'denied') return { tone: 'warn', label: 'Denied' };
  if (o === 'failed') return { tone: 'danger', label: 'Failed' };
  return { tone: 'neutral', label: o || 'unknown' };
}

/** "22 Nov 2026 14:03:21" (local). @param {string | undefined} iso */
export function auditTime(iso) {
  if (!iso) return '—';
  const d = new Date(iso);
  if (Number.isNaN(d.getTime())) return iso;
  return `${d.toLocaleDateString('en-GB', { day: 'numeric', month: 'short', year: 'numeric' })} ${d.toLocaleTimeString('en-GB', { hour: '2-digit', minute: '2-digit', second: '2-digit' })}`;
}
