/**
 * Who is logged in, what the cell config says, and whether we are offline.
 *
 * The last /api/auth/me and /api/config answers are kept in localStorage for display only,
 * so an offline reload can still draw the shell; the server enforces every permission.
 */
import { api as defaultApi } from './api.js';
import { adoptAccountLocale, forgetLocale, switchLocale, isLocale } from './i18n.js';
import { m } from '$lib/paraglide/messages.js';

const CACHE_KEY = 'cell-ui.session.v1';
// Set when logout could not reach the server: the cookie is still valid, so finish it later.
const PENDING_LOGOUT_KEY = 'cell-ui.logout-pending';

/** @typedef {{ username: string, role: string, locale?: string }} User  locale: the language kept with the account */
/** @typedef {{ id: string, title: string }} ConfigPage */
/**
 * GET /api/config: the cell file as this role needs it. The last four fields are newer: code must
 * tolerate their absence (an older BFF, or a cached answer from before an upgrade).
 * @typedef {object} CellConfig
 * @property {{ id: string, name: string, description?: string }} cell
 * @property {string} role
 * @property {ConfigPage[]} pages  the pages this role sees, in menu order, titles from the cell file
 * @property {{ topic: string, type: string, modes: string[] }} operation_mode
 * @property {Record<string, any>} [features]  each visible feature's part of the cell file, by feature id
 * @property {string[]} [commands]  feature ids whose commands this role may send
 * @property {{ take_over: boolean, heartbeat_timeout_s?: number }} [control]  whether this role may take the control lease over; the cell's lease timeout
 * @property {{ service: string, type: string } | null} [stop]  the robot stop service (std_srvs/Trigger),
 *   present for every role that sees any page (whether or not it moves the robot)
 */

/** @typedef {'unknown' | 'authenticated' | 'logged-out'} AuthState */

export class Session {
  /** @type {User | null} */
  user = $state(null);
  /** @type {CellConfig | null} */
  config = $state(null);
  /** @type {AuthState} */
  auth = $state('unknown');
  offline = $state(false);
  /** A login is under way: the login page waits for its end before it leaves. */
  signingIn = $state(false);
  /**
   * The account's language was taken at the login: the next page must be loaded as a new document, in it
   * (not a reload racing the client-side navigation).
   */
  loadNextAfresh = false;

  /**
   * @param {object} [deps]
   * @param {typeof defaultApi} [deps.api]
   * @param {Storage | null} [deps.storage]
   * @param {{ adopt: (locale: unknown, opts?: { reload?: boolean }) => boolean, forget: () => void, switchTo: (locale: any) => void }} [deps.locale]
   *   applying the account's language (the page reloads in it unless reload is false)
   */
  constructor(deps = {}) {
    this.api = deps.api ?? defaultApi;
    this.storage = deps.storage !== undefined ? deps.storage : safeLocalStorage();
    this.locale = deps.locale ?? { adopt: adoptAccountLocale, forget: forgetLocale, switchTo: switchLocale };
  }

  /**
   * Ask the server who we are and what we may see. Offline: fall back to the cache.
   * @param {{ reloadForLocale?: boolean }} [opts] false at a login: a changed language sets loadNextAfresh instead
   * @returns {Promise<AuthState>}
   */
  async refresh({ reloadForLocale = true } = {}) {
    if (this.#get(PENDING_LOGOUT_KEY)) {
      const out = await this.api.logout();
      if (out.kind === 'offline') return this.#goOffline();
      this.#remove(PENDING_LOGOUT_KEY);
    }
    const me = await this.api.me();
    if (me.kind === 'offline') return this.#goOffline();
    if (me.kind === 'unauthorized') return this.#loggedOut();
    if (me.kind !== 'ok') {
      // A 5xx from the BFF is not a logout; keep what we have.
      this.offline = false;
      return this.auth;
    }
    const cfg = await this.api.config();
    if (cfg.kind === 'offline') return this.#goOffline();
    if (cfg.kind === 'unauthorized') return this.#loggedOut();
    this.offline = false;
    this.user = me.data;
    if (cfg.kind === 'ok') this.config = cfg.data;
    this.auth = 'authenticated';
    this.#save();
    // The language chosen on any device follows the account here.
    if (this.locale.adopt(me.data?.locale, { reload: reloadForLocale }) && !reloadForLocale) this.loadNextAfresh = true;
    return this.auth;
  }

  /**
   * @param {string} username @param {string} password
   * @returns {Promise<{ ok: true } | { ok: false, error: string }>}
   */
  async login(username, password) {
    this.signingIn = true;
    try {
      return await this.#login(username, password);
    } finally {
      this.signingIn = false;
    }
  }

  /** @param {string} username @param {string} password */
  async #login(username, password) {
    const r = await this.api.login(username, password);
    if (r.kind === 'offline') {
      this.offline = true;
      return { ok: false, error: m.errors_offline() };
    }
    this.offline = false;
    if (r.kind === 'unauthorized') return { ok: false, error: r.error || m.errors_auth_invalid_credentials() };
    if (r.kind !== 'ok') return { ok: false, error: r.error || m.errors_login_failed() };
    this.user = r.data;
    this.auth = 'authenticated';
    // Pull the role's config right away so the menu is complete on the first screen.
    await this.refresh({ reloadForLocale: false });
    return /** @type {const} */ ({ ok: true });
  }

  /**
   * Keep a language with the account (null: the browser's), then show the app in it.
   * @param {string | null} locale
   * @returns {Promise<{ ok: true } | { ok: false, error: string }>}
   */
  async setLanguage(locale) {
    const r = await this.api.preferences({ locale });
    if (r.kind === 'offline') return { ok: false, error: m.errors_offline() };
    if (r.kind === 'unauthorized') {
      this.expire();
      return { ok: false, error: r.error };
    }
    if (r.kind !== 'ok') return { ok: false, error: r.error };
    this.user = r.data;
    this.#save();
    this.locale.switchTo(isLocale(locale) ? locale : null);
    return { ok: true };
  }

  async logout() {
    // Even offline the local session is dropped; the server side is finished on the next refresh.
    const r = await this.api.logout();
    // The login page follows the browser again, not this user's language.
    this.locale.forget();
    this.#loggedOut();
    if (r.kind === 'offline') this.#set(PENDING_LOGOUT_KEY, '1');
  }

  /** Called by anything that saw a 401 from the server. */
  expire() {
    this.#loggedOut();
  }

  /** @param {boolean} value */
  setOffline(value) {
    this.offline = value;
  }

  /** @returns {AuthState} */
  #goOffline() {
    this.offline = true;
    if (!this.user) {
      const cached = this.#load();
      if (cached) {
        this.user = cached.user;
        this.config = cached.config;
      }
    }
    // With a cached identity we draw the shell; without one there is nothing to show but login.
    this.auth = this.user ? 'authenticated' : 'logged-out';
    return this.auth;
  }

  /** @returns {AuthState} */
  #loggedOut() {
    this.offline = false;
    this.user = null;
    this.config = null;
    this.auth = 'logged-out';
    this.#remove(CACHE_KEY);
    return this.auth;
  }

  #save() {
    this.#set(CACHE_KEY, JSON.stringify({ user: this.user, config: this.config }));
  }

  /** @returns {{ user: User, config: CellConfig | null } | null} */
  #load() {
    try {
      const raw = this.#get(CACHE_KEY);
      const v = raw ? JSON.parse(raw) : null;
      return v && v.user && typeof v.user.username === 'string' ? v : null;
    } catch {
      return null;
    }
  }

  // Storage may be missing or throw (privacy mode, quota): the cache is optional.
  /** @param {string} k */
  #get(k) {
    try {
      return this.storage?.getItem(k) ?? null;
    } catch {
      return null;
    }
  }
  /** @param {string} k @param {string} v */
  #set(k, v) {
    try {
      this.storage?.setItem(k, v);
    } catch {
      /* ignore */
    }
  }
  /** @param {string} k */
  #remove(k) {
    try {
      this.storage?.removeItem(k);
    } catch {
      /* ignore */
    }
  }
}

function safeLocalStorage() {
  try {
    return globalThis.localStorage ?? null;
  } catch {
    return null;
  }
}

export const session = new Session();
