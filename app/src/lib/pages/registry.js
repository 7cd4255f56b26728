/**
 * The app's page registry: the one list that says which feature pages this build knows.
 * Adding a feature page = one entry here + one folder under src/routes/(app)/.
 * The server decides which of these a role may see (GET /api/config -> pages).
 */

/** @typedef {{ id: string, path: string, title: string, icon: string }} PageEntry */

/** @type {PageEntry[]} */
export const registry = [
  { id: 'home', path: '/', title: 'Home', icon: 'home' },
  { id: 'system', path: '/system', title: 'System', icon: 'system' },
];

/** @param {string} id @returns {PageEntry | undefined} */
export function pageById(id) {
  return registry.find((p) => p.id === id);
}

/**
 * The registry entry owning a URL path (exact match after trimming a trailing slash).
 * @param {string} pathname
 * @returns {PageEntry | undefined}
 */
export function pageByPath(pathname) {
  const p = pathname.length > 1 ? pathname.replace(/\/+$/, '') : pathname;
  return registry.find((e) => e.path === p);
}

/**
 * Menu entries: the pages the server allows, in the server's order, limited to the ones
 * this build has a route for. The server's title wins (it comes from the cell file).
 * @param {{ id: string, title?: string }[] | undefined} allowed
 * @param {PageEntry[]} [known]
 * @returns {PageEntry[]}
 */
export function menuPages(allowed, known = registry) {
  if (!Array.isArray(allowed)) return [];
  /** @type {PageEntry[]} */
  const out = [];
  for (const a of allowed) {
    const entry = known.find((k) => k.id === a?.id);
    if (entry && !out.some((o) => o.id === entry.id)) out.push({ ...entry, title: a.title || entry.title });
  }
  return out;
}

/**
 * @param {string} id
 * @param {{ id: string }[] | undefined} allowed
 */
export function isAllowed(id, allowed) {
  return Array.isArray(allowed) && allowed.some((a) => a?.id === id);
}

/**
 * What the shell should draw for a URL, given the pages the role may see.
 * 'denied' never renders the page component, so its API calls are not even made.
 * @param {string} pathname
 * @param {{ id: string }[] | undefined} allowed
 * @returns {{ kind: 'page' | 'denied', entry: PageEntry } | { kind: 'not-found' }}
 */
export function routeAccess(pathname, allowed) {
  const entry = pageByPath(pathname);
  if (!entry) return { kind: 'not-found' };
  return { kind: isAllowed(entry.id, allowed) ? 'page' : 'denied', entry };
}

/**
 * Where to go after login: only same-origin absolute paths, never the login page itself.
 * @param {string | null | undefined} next
 */
export function safeNext(next) {
  if (!next || !next.startsWith('/') || next.startsWith('//') || next.startsWith('/\\')) return '/';
  if (next === '/login' || next.startsWith('/login?') || next.startsWith('/login/')) return '/';
  return next;
}
