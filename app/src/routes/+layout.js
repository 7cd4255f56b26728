// Pure client-side SPA: the BFF serves index.html for every page path.
export const ssr = false;
export const prerender = false;
