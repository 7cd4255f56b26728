// POST /api/auth/login, POST /api/auth/logout, GET /api/auth/me
import { Router } from 'express';
import { sessionOf, setSessionCookie, clearSessionCookie } from '../auth/session.js';

/**
 * @param {{users: import('../auth/users.js').UserStore, tokens: import('../auth/tokens.js').TokenService,
 *   onLogout: (s: {username: string, claims: {jti: string}}) => void, log: (m: string) => void}} deps
 */
export function authRoutes({ users, tokens, onLogout, log }) {
  const r = Router();
  r.post('/api/auth/login', async (req, res) => {
    const { username, password } = req.body;
    const user = await users.authenticate(username, password);
    if (!user) {
      log(`login failed for "${String(username).slice(0, 64)}" from ${req.ip}`);
      return res.status(401).json({ error: 'Invalid user name or password' });
    }
    setSessionCookie(res, tokens.issue(user), req.secure, tokens.ttlS);
    log(`login ${user.username} (${user.role}) from ${req.ip}`);
    res.json(user);
  });
  r.post('/api/auth/logout', (req, res) => {
    const s = sessionOf(req, tokens, users);
    if (s) {
      tokens.revoke(s.claims);
      onLogout(s);
      log(`logout ${s.username}`);
    }
    clearSessionCookie(res, req.secure);
    res.status(204).end();
  });
  r.get('/api/auth/me', (req, res) => {
    const s = req.session;
    if (!s) return res.status(401).json({ error: 'Not logged in' });
    res.json({ username: s.username, role: s.role });
  });
  return r;
}
