/**
 * Follow a CSS media query: `set` gets whether it matches now and on every change. Returns the cleanup, so a
 * component writes `$effect(() => watchMedia('(min-width: 768px)', (m) => (wide = m)))`. Without matchMedia
 * (tests, old browsers) nothing matches.
 * @param {string} query @param {(matches: boolean) => void} set
 * @returns {() => void}
 */
export function watchMedia(query, set) {
  const mq = typeof window !== 'undefined' && typeof window.matchMedia === 'function' ? window.matchMedia(query) : null;
  if (!mq) {
    set(false);
    return () => {};
  }
  set(mq.matches);
  const on = () => set(mq.matches);
  mq.addEventListener('change', on);
  return () => mq.removeEventListener('change', on);
}
