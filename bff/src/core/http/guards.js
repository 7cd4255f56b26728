// Guards every HTTP route uses: a session, and "the role sees this page" (the API behind a page is open to
// exactly the roles that see the page).
import { mayViewPage } from '../access/pages.js';

/** @type {import('express').RequestHandler} */
export function requireSession(req, res, next) {
  if (!req.session) return res.status(401).json({ error: 'Not logged in' });
  next();
}

/** @param {import('../config/cell-types.js').Cell} cell @param {string} pageId @returns {import('express').RequestHandler} */
export function requirePage(cell, pageId) {
  return (req, res, next) => {
    if (!mayViewPage(cell, req.session.role, pageId)) return res.status(403).json({ error: `role "${req.session.role}" may not use ${pageId}` });
    next();
  };
}
