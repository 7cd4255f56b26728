// Where to go after the login: on its own, so the login page does not load the feature list.

/**
 * Where to go after login: only same-origin absolute paths, never the login page itself.
 * @param {string | null | undefined} next
 */
export function safeNext(next) {
  if (!next || !next.startsWith('/') || next.startsWith('//') || next.startsWith('/\\')) return '/';
  if (next === '/login' || next.startsWith('/login?') || next.startsWith('/login/')) return '/';
  return next;
}
