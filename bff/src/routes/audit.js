// GET /api/audit: the audit log, newest first, for roles that see the System page.
import { Router } from 'express';
import { requireSession, requirePage } from './cell.js';

/** @param {{audit: import('../audit/audit-log.js').AuditLog, cell: import('../config/cell-types.js').Cell}} deps */
export function auditRoutes({ audit, cell }) {
  const r = Router();
  r.get('/api/audit', requireSession, requirePage(cell, 'system'), (req, res) => {
    const q = req.query;
    const num = (v, d, max) => { const n = Number(v); return Number.isInteger(n) && n >= 0 ? Math.min(n, max) : d; };
    res.json(audit.query({
      user: typeof q.user === 'string' ? q.user : undefined,
      op: typeof q.op === 'string' ? q.op : undefined,
      outcome: typeof q.outcome === 'string' ? q.outcome : undefined,
      since: typeof q.since === 'string' ? q.since : undefined,
      offset: num(q.offset, 0, 1e9),
      limit: num(q.limit, 50, 500) || 50,
    }));
  });
  return r;
}
