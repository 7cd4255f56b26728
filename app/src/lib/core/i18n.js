/**
 * The user's language: the compiled messages (`m`, from messages/<feature>/<locale>.json), numbers, units, dates and
 * durations through Intl in the user's locale, the cell file's own texts (a string, or one per language), and the
 * BFF's errors by their stable code.
 *
 * Components import `m` from '$lib/paraglide/messages.js' and the formatters from here.
 */
import { getLocale, setLocale, locales, baseLocale } from '$lib/paraglide/runtime.js';

export { getLocale, locales, baseLocale };

/** @typedef {(typeof locales)[number]} Locale */

/** Each language in its own name: a menu of languages must be readable whatever the current one is. */
export const LANGUAGE_NAMES = /** @type {Record<Locale, string>} */ ({ en: 'English', es: 'Español', fi: 'Suomi', de: 'Deutsch' });

/** @param {unknown} v @returns {v is Locale} */
export function isLocale(v) {
  return typeof v === 'string' && /** @type {readonly string[]} */ (locales).includes(v);
}

/**
 * Switch the language (the page reloads: every text is drawn again in it); null: the browser's again.
 * @param {Locale | null} locale
 */
export function switchLocale(locale) {
  if (locale === null) {
    forgetLocale();
    globalThis.location?.reload();
  } else if (locale !== getLocale()) setLocale(locale);
}

/**
 * The account's language after a login or a refresh: apply it when it differs from the one in use.
 * @param {unknown} locale
 * @param {{ reload?: boolean }} [opts] reload false: only keep it; the caller loads the next page afresh
 * @returns {boolean} true when the language changed (and, by default, the page is about to reload in it)
 */
export function adoptAccountLocale(locale, { reload = true } = {}) {
  if (!isLocale(locale) || locale === getLocale()) return false;
  setLocale(locale, { reload });
  return true;
}

/** After a logout the login page follows the browser again, not the last user's choice. */
export function forgetLocale() {
  try {
    localStorage.removeItem('cell-ui.locale');
  } catch {
    /* storage unavailable: nothing kept */
  }
}

/** @type {Map<string, Intl.NumberFormat>} */
const numberFormats = new Map();

/**
 * A number in the user's locale ("1 234,5" in Finnish).
 * @param {number | null | undefined} n
 * @param {Intl.NumberFormatOptions} [opts]
 * @returns {string} '–' for a missing or non-finite value
 */
export function fmtNumber(n, opts = {}) {
  if (n === null || n === undefined || !Number.isFinite(n)) return '–';
  const key = getLocale() + JSON.stringify(opts);
  let f = numberFormats.get(key);
  if (!f) numberFormats.set(key, (f = new Intl.NumberFormat(getLocale(), opts)));
  return f.format(n);
}

/**
 * A number with a fixed count of decimals, as toFixed gives it but in the user's locale.
 * @param {number | null | undefined} n
 * @param {number} digits
 */
export function fmtFixed(n, digits) {
  return fmtNumber(n, { minimumFractionDigits: digits, maximumFractionDigits: digits, useGrouping: false });
}

/**
 * A duration in seconds, short ("1 h 2 min 5 s", "2,5 s" in Spanish); under a minute with `decimals` decimals.
 * @param {number | null | undefined} seconds
 * @param {number} [decimals]
 */
export function fmtDuration(seconds, decimals = 1) {
  if (seconds === null || seconds === undefined || !Number.isFinite(seconds)) return '–';
  const unit = (/** @type {string} */ u, /** @type {number} */ v, /** @type {number} */ d = 0) =>
    fmtNumber(v, { style: 'unit', unit: u, unitDisplay: 'short', maximumFractionDigits: d, minimumFractionDigits: d });
  const s = Math.abs(seconds);
  const sign = seconds < 0 ? '-' : '';
  if (s < 60) return sign + unit('second', s, decimals);
  const h = Math.floor(s / 3600);
  const min = Math.floor((s % 3600) / 60);
  const sec = Math.floor(s % 60);
  const parts = [];
  if (h) parts.push(unit('hour', h));
  if (min || h) parts.push(unit('minute', min));
  if (!h) parts.push(unit('second', sec));
  return sign + parts.join(' ');
}

/**
 * A date and time (ms since the epoch or a Date) in the user's locale.
 * @param {number | Date} t
 * @param {Intl.DateTimeFormatOptions} [opts]  default: date and time, medium
 */
export function fmtDateTime(t, opts = { dateStyle: 'medium', timeStyle: 'medium' }) {
  const d = t instanceof Date ? t : new Date(t);
  if (Number.isNaN(d.getTime())) return '–';
  return new Intl.DateTimeFormat(getLocale(), opts).format(d);
}

/** @param {number | Date} t  the time of day, with seconds */
export function fmtTime(t) {
  return fmtDateTime(t, { timeStyle: 'medium' });
}

/**
 * A text from the cell file: a plain string, or one per language (`{en: 'Pick', es: 'Recoger'}`). A missing
 * language falls back to English (then to any); in development the fallback is marked so it is seen and filled.
 * @param {unknown} text
 * @returns {string}
 */
export function cellText(text) {
  if (typeof text === 'string') return text;
  if (!text || typeof text !== 'object') return '';
  const byLang = /** @type {Record<string, unknown>} */ (text);
  const here = byLang[getLocale()];
  if (typeof here === 'string') return here;
  const fallback = typeof byLang[baseLocale] === 'string' ? byLang[baseLocale] : Object.values(byLang).find((v) => typeof v === 'string');
  if (typeof fallback !== 'string') return '';
  return import.meta.env?.DEV ? `[${baseLocale}] ${fallback}` : fallback;
}
