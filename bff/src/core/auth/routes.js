// POST /api/auth/login, POST /api/auth/logout, GET /api/auth/me, PUT /api/auth/me/preferences
import { Router } from 'express';
import { errorBody } from '../http/errors.js';
import { setSessionCookie, clearSessionCookie } from './session.js';

/**
 * @param {{users: import('../auth/users.js').UserStore, tokens: import('../auth/tokens.js').TokenService,
 *   throttle: import('../auth/throttle.js').LoginThrottle, audit: import('../audit/audit-log.js').AuditLog,
 *   onLogout: (s: {username: string, sid: string}) => void}} deps
 */
export function authRoutes({ users, tokens, throttle, audit, onLogout }) {
  const r = Router();
  r.post('/api/auth/login', async (req, res) => {
    // The document's validation ran before (400/415); still never trust the shape of a body here.
    const { username, password } = req.body && typeof req.body === 'object' ? req.body : {};
    if (typeof username !== 'string' || typeof password !== 'string') return res.status(400).json(errorBody('expected {"username": string, "password": string}', 'request.invalid', { detail: 'username, password' }));
    const keys = [`user:${username}`, `ip:${req.ip}`];
    const entry = { user: String(username).slice(0, 64), role: null, ip: req.ip || null, op: 'login' };
    const wait = throttle.retryAfter(keys);
    if (wait > 0) {
      audit.record({ ...entry, outcome: 'denied', detail: 'throttled' });
      res.setHeader('Retry-After', String(wait));
      return res.status(429).json(errorBody(`Too many failed attempts. Try again in ${wait} s.`, 'auth.throttled', { seconds: wait }));
    }
    const user = await users.authenticate(username, password);
    if (!user) {
      throttle.fail(keys);
      audit.record({ ...entry, outcome: 'denied', detail: 'wrong user name or password' });
      return res.status(401).json(errorBody('Invalid user name or password', 'auth.invalid_credentials'));
    }
    throttle.succeed(keys);
    setSessionCookie(res, tokens.issue(user), req.secure, tokens.ttlS);
    audit.record({ ...entry, role: user.role, outcome: 'ok' });
    res.json(user);
  });
  r.post('/api/auth/logout', (req, res) => {
    const s = req.session;
    if (s) {
      tokens.revoke(s.claims);
      onLogout(s);
      audit.record({ user: s.username, role: s.role, ip: req.ip || null, op: 'logout', outcome: 'ok' });
    }
    clearSessionCookie(res, req.secure);
    res.status(204).end();
  });
  r.get('/api/auth/me', (req, res) => {
    const s = req.session;
    if (!s) return res.status(401).json(errorBody('Not logged in', 'auth.not_logged_in'));
    // The role is the token's; the language is the account's now (chosen on another device, too).
    const locale = users.profile(s.username)?.locale;
    res.json({ username: s.username, role: s.role, ...(locale ? { locale } : {}) });
  });
  r.put('/api/auth/me/preferences', (req, res) => {
    const s = req.session;
    if (!s) return res.status(401).json(errorBody('Not logged in', 'auth.not_logged_in'));
    // The document's validation ran before: locale is one of the app's languages or null.
    const locale = req.body.locale ?? null;
    try {
      const u = users.setLocale(s.username, locale);
      audit.record({ user: s.username, role: s.role, ip: req.ip || null, op: 'preferences', target: 'locale', outcome: 'ok', detail: String(locale) });
      res.json({ ...u, role: s.role });
    } catch (e) {
      // The account was removed while its token lives on.
      audit.record({ user: s.username, role: s.role, ip: req.ip || null, op: 'preferences', target: 'locale', outcome: 'denied', detail: String(e.message) });
      res.status(409).json(errorBody(String(e.message), 'auth.no_account'));
    }
  });
  return r;
}
