// GET /api/config (any role, filtered), GET /api/system (admin page).
import { Router } from 'express';
import { configFor, mayViewPage } from '../access/pages.js';

/**
 * @param {{cell: import('../config/cell-types.js').Cell, cellFile: string, users: import('../auth/users.js').UserStore,
 *   healthReport: () => Promise<object>}} deps
 */
export function cellRoutes({ cell, cellFile, users, healthReport }) {
  const r = Router();
  r.get('/api/config', requireSession, (req, res) => {
    res.json(configFor(cell, req.session.role));
  });
  r.get('/api/system', requireSession, requirePage(cell, 'system'), async (req, res) => {
    res.json({
      cell_file: cellFile,
      cell: cell.cell,
      roles: Object.entries(cell.roles).map(([name, def]) => ({ name, title: def.title || name, pages: def.pages })),
      users: users.list(),
      health: await healthReport(),
    });
  });
  return r;
}

/** @type {import('express').RequestHandler} */
export function requireSession(req, res, next) {
  if (!req.session) return res.status(401).json({ error: 'Not logged in' });
  next();
}

/** The API behind a page is open to exactly the roles that see the page. */
export function requirePage(cell, pageId) {
  /** @type {import('express').RequestHandler} */
  return (req, res, next) => {
    if (!mayViewPage(cell, req.session.role, pageId)) return res.status(403).json({ error: `role "${req.session.role}" may not use ${pageId}` });
    next();
  };
}
