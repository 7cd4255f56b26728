// Guards every HTTP route uses: a session, and "the role sees this page" (the API behind a page is open to
// exactly the roles that see the page).
import { mayViewPage } from '../access/pages.js';
import { errorBody } from './errors.js';

/** @type {import('express').RequestHandler} */
export function requireSession(req, res, next) {
  if (!req.session) return res.status(401).json(errorBody('Not logged in', 'auth.not_logged_in'));
  next();
}

/** @param {import('../config/cell-types.js').Cell} cell @param {string} pageId @returns {import('express').RequestHandler} */
export function requirePage(cell, pageId) {
  return (req, res, next) => {
    if (!mayViewPage(cell, req.session.role, pageId)) return res.status(403).json(errorBody(`role "${req.session.role}" may not use ${pageId}`, 'access.page_denied', { role: req.session.role, page: pageId }));
    next();
  };
}
