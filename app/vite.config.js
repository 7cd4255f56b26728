import { sveltekit } from '@sveltejs/kit/vite';
import { SvelteKitPWA } from '@vite-pwa/sveltekit';
import { defineConfig } from 'vite';
import { paraglideVitePlugin } from '@inlang/paraglide-js';
import { i18nOptions } from './i18n.config.js';

// (process via globalThis: the app's checkJs has no Node types.)
const env = /** @type {any} */ (globalThis).process.env;
const bff = `http://127.0.0.1:${env.BFF_PORT || 8080}`;
const testing = !!env.VITEST;

export default defineConfig({
  plugins: [
    // Unit tests run on messages compiled beforehand (`npm test`): the plugin's watcher keeps Vitest from exiting.
    !testing && paraglideVitePlugin(i18nOptions),
    sveltekit(),
    // The service worker is irrelevant to unit tests and slows them down.
    !testing &&
      SvelteKitPWA({
        registerType: 'autoUpdate',
        injectRegister: false,
        strategies: 'generateSW',
        // Absolute: the default './sw.js' would resolve against deep URLs like /a/b and fail.
        base: '/',
        scope: '/',
        // Without these two the offline navigation fallback (index.html) is not precached.
        kit: { spa: true, adapterFallback: 'index.html' },
        includeAssets: ['favicon.svg', 'icons/*.png'],
        manifest: {
          name: 'Robot Cell',
          short_name: 'Cell',
          description: 'Run and watch a ROS robot cell from a phone, a tablet or a PC.',
          theme_color: '#0f172a',
          background_color: '#0f172a',
          display: 'standalone',
          start_url: '/',
          scope: '/',
          icons: [
            { src: '/icons/icon-192.png', sizes: '192x192', type: 'image/png', purpose: 'any' },
            { src: '/icons/icon-512.png', sizes: '512x512', type: 'image/png', purpose: 'any' },
            { src: '/icons/maskable-192.png', sizes: '192x192', type: 'image/png', purpose: 'maskable' },
            { src: '/icons/maskable-512.png', sizes: '512x512', type: 'image/png', purpose: 'maskable' },
          ],
        },
        workbox: {
          globPatterns: ['**/*.{js,css,html,svg,png,webmanifest}'],
          navigateFallback: '/index.html',
          // API, rosbridge socket, the CA download and its trust page must always hit the server.
          navigateFallbackDenylist: [/^\/api\//, /^\/ros/, /^\/ca\.crt/, /^\/trust/],
          cleanupOutdatedCaches: true,
          // Take over the page that installed the worker, so the first visit is already offline-capable.
          clientsClaim: true,
          skipWaiting: true,
        },
      }),
  ],
  build: {
    // The app's many tiny shared chunks (half under 2 kB) merged into their neighbours: each module a page loads
    // costs the main thread a request and a module record, on a slow phone even from the service worker.
    rollupOptions: { output: { experimentalMinChunkSize: 8_000 } },
  },
  server: {
    proxy: {
      '/api': { target: bff, changeOrigin: false },
      '/ros': { target: bff, ws: true, changeOrigin: false },
    },
  },
  resolve: testing ? { conditions: ['browser'] } : undefined,
  test: {
    environment: 'jsdom',
    // Worker threads rather than child processes: the same isolation per file, a fifth less time on CI's 2 cores.
    pool: 'threads',
    include: ['src/**/*.test.js', 'tests/**/*.test.js'],
    setupFiles: ['tests/setup.js'],
    restoreMocks: true,
  },
});
