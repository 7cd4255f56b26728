// Cookie session: who is calling, checked against the current users file on every request
// (a removed user or a changed role takes effect at once).
import * as cookie from 'cookie';

export const COOKIE = 'cell_session';

/**
 * @param {import('node:http').IncomingMessage} req
 * @param {import('./tokens.js').TokenService} tokens
 * @param {import('./users.js').UserStore} users
 * @returns {null | {username: string, role: string, sid: string, claims: import('./tokens.js').Claims}}
 */
export function sessionOf(req, tokens, users) {
  const jar = cookie.parse(req.headers.cookie || '');
  const claims = tokens.verify(jar[COOKIE]);
  if (!claims) return null;
  const u = users.get(claims.sub);
  if (!u || u.role !== claims.role) return null;
  return { username: u.username, role: u.role, sid: claims.sid, claims };
}

/** @param {import('express').Response} res @param {string} token @param {boolean} secure @param {number} maxAgeS */
export function setSessionCookie(res, token, secure, maxAgeS) {
  res.setHeader('Set-Cookie', cookie.serialize(COOKIE, token, {
    httpOnly: true, sameSite: 'strict', secure, path: '/', maxAge: maxAgeS,
  }));
}

/** @param {import('express').Response} res @param {boolean} secure */
export function clearSessionCookie(res, secure) {
  res.setHeader('Set-Cookie', cookie.serialize(COOKIE, '', { httpOnly: true, sameSite: 'strict', secure, path: '/', maxAge: 0 }));
}
