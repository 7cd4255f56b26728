// Types for the PWA plugin's virtual modules (used by src/routes/+layout.svelte), for checkJs.
/// <reference types="vite-plugin-pwa/info" />
/// <reference types="vite-plugin-pwa/vanillajs" />
export {};
