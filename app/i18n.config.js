// The message compiler's options, shared by the Vite build (and Vitest) and `npm run typecheck`.
// Catalogues: messages/<feature>/<locale>.json, listed in project.inlang/settings.json. Each page's bundle carries
// only the messages it uses. The locale: the user's choice (kept with the account, mirrored in localStorage),
// else the browser's, else English.
export const i18nOptions = {
  project: './project.inlang',
  outdir: './src/lib/paraglide',
  strategy: /** @type {any} */ (['localStorage', 'preferredLanguage', 'baseLocale']),
  localStorageKey: 'cell-ui.locale',
  emitReadme: false,
};
