/**
 * The drawn theme's colours for what CSS cannot paint: a canvas (three.js, Chart.js) reads them from the root's
 * custom properties (app.css: --scene-*, --chart-*, --text-2, --border), and draws again when the theme changes.
 */

/**
 * A colour of the drawn theme.
 * @param {string} name  a custom property, e.g. '--chart-1'
 * @param {string} fallback  when the property is not there (a test without the stylesheet)
 * @param {Element | undefined} [root]
 * @returns {string}
 */
export function themeColor(name, fallback, root = globalThis.document?.documentElement) {
  const v = root ? getComputedStyle(root).getPropertyValue(name).trim() : '';
  return v || fallback;
}

/**
 * Call `fn` whenever the drawn theme changes (the root's data-theme, set by core/display.svelte.js).
 * @param {() => void} fn
 * @param {Element | undefined} [root]
 * @returns {() => void} stop
 */
export function onThemeChange(fn, root = globalThis.document?.documentElement) {
  if (!root || typeof MutationObserver !== 'function') return () => {};
  const obs = new MutationObserver(() => fn());
  obs.observe(root, { attributes: true, attributeFilter: ['data-theme'] });
  return () => obs.disconnect();
}
