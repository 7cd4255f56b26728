// After `vite build`: the SPA fallback page (build/index.html) also preloads the modules, and links the styles, of the login
// route and the root error page. The fallback does not know which route it will serve, so SvelteKit preloads only
// the root layout; the login route's nodes were then requested after the app had started, a round of ~300 ms at 4x
// CPU even from the service worker (issue 29: warm login within 1 s). The login page is where a session begins.
// The service worker's revision of index.html follows _app/version.json, so editing the file here is safe.
import { readFileSync, readdirSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';

const ROUTES = ['src/routes/login/+page.svelte', 'src/routes/+error.svelte'];
const root = new URL('.', import.meta.url).pathname;
const nodesDir = join(root, '.svelte-kit/generated/client-optimized/nodes');
const manifestPath = join(root, '.svelte-kit/output/client/.vite/manifest.json');
const fallbackPath = join(root, 'build/index.html');

/** @typedef {{ file: string, imports?: string[], css?: string[] }} Chunk */
/** @type {Record<string, Chunk>} */
const manifest = JSON.parse(readFileSync(manifestPath, 'utf8'));

/** The generated node modules (`nodes/N.js`) that export the given route files. */
const nodeKeys = readdirSync(nodesDir)
  .filter((f) => ROUTES.some((r) => readFileSync(join(nodesDir, f), 'utf8').includes(`/${r}"`)))
  .map((f) => `.svelte-kit/generated/client-optimized/nodes/${f}`);
if (nodeKeys.length !== ROUTES.length) {
  throw new Error(`preload-fallback: found ${nodeKeys.length} of ${ROUTES.length} route nodes (${ROUTES.join(', ')})`);
}

/** @type {Set<string>} */ const scripts = new Set();
/** @type {Set<string>} */ const styles = new Set();
/** @param {string} key */
function walk(key) {
  const chunk = manifest[key];
  if (!chunk) throw new Error(`preload-fallback: ${key} is not in the Vite manifest`);
  if (scripts.has(chunk.file)) return;
  scripts.add(chunk.file);
  for (const c of chunk.css ?? []) styles.add(c);
  for (const i of chunk.imports ?? []) walk(i);
}
nodeKeys.forEach(walk);

let html = readFileSync(fallbackPath, 'utf8');
const missing = (/** @type {string} */ f) => !html.includes(`"/${f}"`);
const links = [
  ...[...scripts].filter(missing).map((f) => `<link href="/${f}" rel="modulepreload">`),
  // As stylesheets, not preloads: a route's import waits for its styles, and Vite's loader skips a stylesheet the
  // page has (a preload it would request again, late). They are the login route's own, scoped by Svelte.
  ...[...styles].filter(missing).map((f) => `<link href="/${f}" rel="stylesheet">`),
];
if (links.length) {
  const head = html.indexOf('</head>');
  if (head < 0) throw new Error('preload-fallback: build/index.html has no </head>');
  const at = html.lastIndexOf('\n', head) + 1;
  html = `${html.slice(0, at)}${links.map((l) => `\t\t${l}\n`).join('')}${html.slice(at)}`;
  writeFileSync(fallbackPath, html);
}
console.log(`preload-fallback: ${links.length} preloads added for ${ROUTES.join(', ')}`);
