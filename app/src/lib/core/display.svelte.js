/**
 * How the app looks on this device: the theme (as the device, light, dark, high contrast) and glove mode (every
 * control at least 64 px). Kept per device, not with the account: the glare on a phone and a dim control room
 * belong to the place, not the person. app.html applies the same before the first paint (keep the two in step).
 */

export const DISPLAY_KEY = 'cell-ui.display';
export const THEMES = /** @type {const} */ (['system', 'light', 'dark', 'contrast']);
/** @typedef {(typeof THEMES)[number]} Theme */

/**
 * The theme drawn: the device's setting decides for 'system' (more contrast wins over dark).
 * @param {Theme} theme @param {(q: string) => boolean} matches
 * @returns {'light' | 'dark' | 'contrast'}
 */
export function resolveTheme(theme, matches) {
  if (theme !== 'system') return theme;
  if (matches('(prefers-contrast: more)') || matches('(forced-colors: active)')) return 'contrast';
  return matches('(prefers-color-scheme: dark)') ? 'dark' : 'light';
}

export class Display {
  /** @type {Theme} */
  theme = $state('system');
  glove = $state(false);

  /**
   * @param {object} [deps]
   * @param {Storage | null} [deps.storage]
   * @param {HTMLElement | null} [deps.root]
   * @param {(q: string) => MediaQueryList | null} [deps.media]
   */
  constructor(deps = {}) {
    this.storage = deps.storage !== undefined ? deps.storage : safe(() => globalThis.localStorage);
    this.root = deps.root !== undefined ? deps.root : safe(() => globalThis.document.documentElement);
    this.media = deps.media ?? ((q) => safe(() => globalThis.matchMedia(q)));
    try {
      const saved = JSON.parse(this.storage?.getItem(DISPLAY_KEY) ?? 'null');
      if (saved && THEMES.includes(saved.theme)) this.theme = saved.theme;
      if (saved && typeof saved.glove === 'boolean') this.glove = saved.glove;
    } catch {
      /* a broken entry is the defaults */
    }
  }

  /** Draw the current choice, and follow the device's setting while the theme is 'system'. @returns {() => void} stop following */
  start() {
    this.apply();
    const queries = ['(prefers-color-scheme: dark)', '(prefers-contrast: more)', '(forced-colors: active)'].map((q) => this.media(q)).filter((q) => q !== null);
    const on = () => this.apply();
    for (const q of queries) q.addEventListener?.('change', on);
    return () => queries.forEach((q) => q.removeEventListener?.('change', on));
  }

  /** @param {Theme} theme */
  setTheme(theme) {
    this.theme = theme;
    this.#save();
  }

  /** @param {boolean} on */
  setGlove(on) {
    this.glove = on;
    this.#save();
  }

  /** The theme drawn now. */
  get drawn() {
    return resolveTheme(this.theme, (q) => this.media(q)?.matches === true);
  }

  apply() {
    if (!this.root) return;
    this.root.dataset.theme = this.drawn;
    if (this.glove) this.root.dataset.glove = '';
    else delete this.root.dataset.glove;
  }

  #save() {
    try {
      this.storage?.setItem(DISPLAY_KEY, JSON.stringify({ theme: this.theme, glove: this.glove }));
    } catch {
      /* storage unavailable: the choice lasts this visit */
    }
    this.apply();
  }
}

/** @template T @param {() => T} f @returns {T | null} */
function safe(f) {
  try {
    return f() ?? null;
  } catch {
    return null;
  }
}

export const display = new Display();
