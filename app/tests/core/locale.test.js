// The user's language: formatters in the locale, cell-file texts per language, page titles, BFF errors by code,
// the account's language applied, the display settings.
import { afterEach, describe, expect, it, vi } from 'vitest';
import { setLocale, getLocale } from '../../src/lib/paraglide/runtime.js';
import { cellText, fmtDuration, fmtFixed, fmtNumber, isLocale } from '../../src/lib/core/i18n.js';
import { cellTitle, menuPages, pageTitle, routeAccess } from '../../src/lib/core/routing.js';
import { errorText } from '../../src/lib/core/errors.js';
import { Display, resolveTheme } from '../../src/lib/core/display.svelte.js';
import { Session } from '../../src/lib/core/session.svelte.js';

/** @param {string} l */
const speak = (l) => setLocale(/** @type {any} */ (l), { reload: false });
afterEach(() => speak('en'));

describe('formatting in the locale', () => {
  it('numbers and fixed decimals follow the language', () => {
    expect(fmtFixed(1234.5, 2)).toBe('1234.50');
    speak('es');
    expect(fmtFixed(1234.5, 2)).toBe('1234,50');
    expect(fmtNumber(12345.6)).toMatch(/^12\.345,6$/);
    speak('fi');
    expect(fmtFixed(-0.5, 1)).toMatch(/^[−-]0,5$/);
    speak('de');
    expect(fmtNumber(0.25, { style: 'percent' })).toMatch(/^25\s?%$/);
    expect(fmtNumber(NaN)).toBe('–');
  });
  it('durations: seconds with decimals under a minute, whole units above', () => {
    expect(fmtDuration(4.25)).toBe('4.3 sec');
    expect(fmtDuration(125)).toBe('2 min 5 sec');
    expect(fmtDuration(3725)).toBe('1 hr 2 min');
    speak('es');
    expect(fmtDuration(4.25)).toMatch(/^4,3\s?s$/);
    expect(fmtDuration(null)).toBe('–');
  });
});

describe('texts from the cell file', () => {
  it('a string as it is, a text per language in the user\'s, English when the language is missing (marked in development)', () => {
    expect(cellText('Pick part')).toBe('Pick part');
    const t = { en: 'Pick part', es: 'Recoger pieza' };
    expect(cellText(t)).toBe('Pick part');
    speak('es');
    expect(cellText(t)).toBe('Recoger pieza');
    speak('fi');
    expect(cellText(t)).toBe('[en] Pick part');
    expect(cellText(undefined)).toBe('');
  });
  it('a page title left at the English default is translated; the cell file\'s own title wins', () => {
    speak('es');
    // The list's titles are taken in the language of the page load (a change of language reloads it).
    const icon = 'M0 0';
    const load = async () => ({ default: /** @type {any} */ (null) });
    const list = [
      { id: 'home', path: '/', title: 'Inicio', title_en: 'Home', icon, load },
      { id: 'process', path: '/process', title: 'Proceso', title_en: 'Process', icon, load },
    ];
    const [home, proc] = menuPages([{ id: 'home', title: 'Home' }, { id: 'process', title: { en: 'Line 3', es: 'Línea 3' } }], list);
    expect(home.title).toBe('Inicio');
    expect(proc.title).toBe('Línea 3');
    expect(cellTitle('My cell page', home)).toBe('My cell page');
    expect(pageTitle(routeAccess('/nowhere', []), [])).toBe('No encontrado');
  });
});

describe('errors from the BFF', () => {
  it('a known code is said in the language with its values; an unknown one shows the English text', () => {
    speak('de');
    expect(errorText({ error: 'Too many failed attempts. Try again in 30 s.', code: 'auth.throttled', params: { seconds: 30 } })).toBe('Zu viele Fehlversuche. In 30 s erneut versuchen.');
    expect(errorText({ error: 'the file is broken', code: 'database.something_new' })).toBe('the file is broken');
    expect(errorText({ code: 'toString' })).toBe('');
    expect(errorText(null)).toBe('');
  });
  it('database: a wrong extension and a malformed CSV, in Spanish; a file without an extension has its own sentence', () => {
    speak('es');
    expect(errorText({ error: 'parts.csv needs a .csv file, not .txt', code: 'database.bad_extension', params: { file: 'parts.csv', expected: '.csv', got: '.txt' } }))
      .toBe('parts.csv necesita un archivo .csv, no .txt.');
    expect(errorText({ error: 'parts.csv needs a .csv file, not one without extension', code: 'database.bad_extension', params: { file: 'parts.csv', expected: '.csv', got: '' } }))
      .toBe('parts.csv necesita un archivo .csv, no uno sin extensión.');
    expect(errorText({
      error: 'parts.csv not replaced: CSV line 2 has 3 columns, expected 2 (as in the first line)',
      code: 'database.csv_columns', params: { file: 'parts.csv', line: 2, columns: 3, expected: 2 },
    })).toBe('parts.csv no se sustituyó: el número de columnas de la línea 2 del CSV es 3 y debería ser 2 (como en la primera línea).');
  });
  it('scene: a ROS master that does not answer, in German', () => {
    speak('de');
    expect(errorText({ error: 'the ROS master at http://cell:11311 does not answer: the URDF parameter cannot be read', code: 'scene.master_down', params: { master: 'http://cell:11311' } }))
      .toBe('Der ROS-Master unter http://cell:11311 antwortet nicht: Der URDF-Parameter kann nicht gelesen werden.');
  });
  it('recorder: a role that may not delete, in German', () => {
    speak('de');
    expect(errorText({ error: 'role operator may not delete recordings', code: 'recorder.delete_denied', params: { role: 'operator' } }))
      .toBe('Ihre Rolle (operator) darf keine Aufzeichnungen löschen.');
  });
});

describe("the account's language", () => {
  /** @param {Record<string, any>} answers */
  const api = (answers) => /** @type {any} */ ({
    me: async () => answers.me, config: async () => ({ kind: 'ok', status: 200, data: { pages: [] } }), logout: async () => ({ kind: 'ok' }),
    preferences: vi.fn(async (/** @type {any} */ body) => answers.preferences ?? { kind: 'ok', status: 200, data: { username: 'ann', role: 'operator', ...body } }),
  });
  it('is applied after a refresh, kept with the account when chosen, and forgotten at logout', async () => {
    const locale = { adopt: vi.fn(() => false), forget: vi.fn(), switchTo: vi.fn() };
    const a = api({ me: { kind: 'ok', status: 200, data: { username: 'ann', role: 'operator', locale: 'fi' } } });
    const s = new Session({ api: a, storage: null, locale });
    await s.refresh();
    expect(locale.adopt).toHaveBeenCalledWith('fi', { reload: true });
    expect(s.loadNextAfresh).toBe(false);
    expect(await s.setLanguage('es')).toEqual({ ok: true });
    expect(a.preferences).toHaveBeenCalledWith({ locale: 'es' });
    expect(locale.switchTo).toHaveBeenLastCalledWith('es');
    expect(s.user?.locale).toBe('es');
    await s.setLanguage(null);
    expect(locale.switchTo).toHaveBeenLastCalledWith(null);
    await s.logout();
    expect(locale.forget).toHaveBeenCalled();
  });
  it('taken at a login without a reload: the login page loads the next page afresh, once the login has finished', async () => {
    const locale = { adopt: vi.fn(() => true), forget: vi.fn(), switchTo: vi.fn() };
    const a = api({ me: { kind: 'ok', status: 200, data: { username: 'ann', role: 'operator', locale: 'fi' } } });
    a.login = async () => ({ kind: 'ok', status: 200, data: { username: 'ann', role: 'operator', locale: 'fi' } });
    const s = new Session({ api: a, storage: null, locale });
    const during = s.login('ann', 'pw');
    expect(s.signingIn).toBe(true);
    expect(await during).toEqual({ ok: true });
    expect(s.signingIn).toBe(false);
    expect(locale.adopt).toHaveBeenCalledWith('fi', { reload: false });
    expect(s.loadNextAfresh).toBe(true);
  });
  it('a refused or offline save changes nothing and says why', async () => {
    const locale = { adopt: vi.fn(() => false), forget: vi.fn(), switchTo: vi.fn() };
    const s = new Session({ api: api({ me: { kind: 'ok', status: 200, data: { username: 'ann', role: 'operator' } }, preferences: { kind: 'offline', error: 'x' } }), storage: null, locale });
    expect(await s.setLanguage('de')).toEqual({ ok: false, error: 'Offline: cannot reach the server.' });
    expect(locale.switchTo).not.toHaveBeenCalled();
    expect(isLocale('de')).toBe(true);
    expect(isLocale('xx')).toBe(false);
    expect(getLocale()).toBe('en');
  });
});

describe('display settings', () => {
  it('follow the device unless chosen; glove mode and the theme are kept and drawn on the root', () => {
    const store = new Map();
    const storage = /** @type {any} */ ({ getItem: (/** @type {string} */ k) => store.get(k) ?? null, setItem: (/** @type {string} */ k, /** @type {string} */ v) => store.set(k, v) });
    const root = document.createElement('html');
    let dark = true;
    const media = (/** @type {string} */ q) => /** @type {any} */ ({ matches: q.includes('dark') && dark, addEventListener() {}, removeEventListener() {} });
    const d = new Display({ storage, root, media });
    d.start();
    expect(root.dataset.theme).toBe('dark');
    dark = false;
    d.apply();
    expect(root.dataset.theme).toBe('light');
    d.setTheme('contrast');
    d.setGlove(true);
    expect(root.dataset.theme).toBe('contrast');
    expect('glove' in root.dataset).toBe(true);
    const again = new Display({ storage, root: document.createElement('html'), media });
    expect([again.theme, again.glove]).toEqual(['contrast', true]);
    expect(resolveTheme('system', (q) => q === '(prefers-contrast: more)')).toBe('contrast');
  });
});
