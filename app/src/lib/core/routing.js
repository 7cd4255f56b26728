/**
 * Routing and the menu, from the feature list (features/index.js). The server decides which features a
 * role may see (GET /api/config -> pages); the list says which ones this build has.
 * Every function takes the list as its last argument (default: the app's), so tests can add features.
 */
import { features as appFeatures } from '../features/index.js';
import { m } from '$lib/paraglide/messages.js';
import { cellText } from './i18n.js';

/** @typedef {import('../features/index.js').FeatureEntry} FeatureEntry */

/** @param {string} id @param {FeatureEntry[]} [list] @returns {FeatureEntry | undefined} */
export function featureById(id, list = appFeatures) {
  return list.find((p) => p.id === id);
}

/**
 * The feature owning a URL path (exact match after trimming a trailing slash).
 * @param {string} pathname
 * @param {FeatureEntry[]} [list]
 * @returns {FeatureEntry | undefined}
 */
export function featureByPath(pathname, list = appFeatures) {
  const p = pathname.length > 1 ? pathname.replace(/\/+$/, '') : pathname;
  return list.find((e) => e.path === p);
}

/**
 * Menu entries: the pages the server allows, in the server's order, limited to the features this
 * build has. The server's title wins (it comes from the cell file).
 * @param {{ id: string, title?: unknown }[] | undefined} allowed
 * @param {FeatureEntry[]} [list]
 * @returns {FeatureEntry[]}
 */
export function menuPages(allowed, list = appFeatures) {
  if (!Array.isArray(allowed)) return [];
  /** @type {FeatureEntry[]} */
  const out = [];
  for (const a of allowed) {
    const entry = list.find((k) => k.id === a?.id);
    if (entry && !out.some((o) => o.id === entry.id)) out.push({ ...entry, title: cellTitle(a.title, entry) });
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
 * 'denied' never loads the page component, so its API calls are not even made.
 * @param {string} pathname
 * @param {{ id: string }[] | undefined} allowed
 * @param {FeatureEntry[]} [list]
 * @returns {{ kind: 'page' | 'denied', entry: FeatureEntry } | { kind: 'not-found' }}
 */
export function routeAccess(pathname, allowed, list = appFeatures) {
  const entry = featureByPath(pathname, list);
  if (!entry) return { kind: 'not-found' };
  return { kind: isAllowed(entry.id, allowed) ? 'page' : 'denied', entry };
}

/**
 * The page title: the cell file's title for the feature when the role sees it, else the list's.
 * @param {ReturnType<typeof routeAccess>} access
 * @param {{ id: string, title?: unknown }[] | undefined} allowed
 */
export function pageTitle(access, allowed) {
  if (access.kind === 'not-found') return m.nav_not_found();
  if (access.kind === 'denied') return m.nav_access_denied();
  const id = access.entry.id;
  return cellTitle(Array.isArray(allowed) ? allowed.find((a) => a?.id === id)?.title : undefined, access.entry);
}

/**
 * A page's title from the cell file (a string, or one per language) in the user's language. A plain title equal to
 * the feature's English default is the default: the app's translation of it is shown.
 * @param {unknown} fromCell @param {FeatureEntry} entry
 */
export function cellTitle(fromCell, entry) {
  if (!fromCell || (typeof fromCell === 'string' && fromCell === entry.title_en)) return entry.title;
  return cellText(fromCell) || entry.title;
}

/**
 * The top bar's "Stop robot": on every page for every role that sees any page, the same rule as the BFF's (it sends
 * `stop` in /api/config to such a role and lets it call that service without the control lease), a role that never
 * moves the robot included: whoever watches the cell must be able to stop it. Null: no button (no page, or a cell
 * without a robot stop).
 * @param {{ pages?: { id: string }[], stop?: { service: string, type?: string } | null } | null | undefined} config
 * @returns {{ service: string, type: string } | null}
 */
export function robotStop(config) {
  const stop = config?.stop;
  if (!stop || typeof stop.service !== 'string' || !stop.service) return null;
  if (!Array.isArray(config?.pages) || config.pages.length === 0) return null;
  return { service: stop.service, type: stop.type || 'std_srvs/Trigger' };
}

export { safeNext } from './safe-next.js';
