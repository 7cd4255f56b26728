// Serves the built PWA: hashed assets cached forever, the shell and the service worker never cached,
// and index.html for any other non-API path (the SPA router takes it from there).
import express from 'express';
import fs from 'node:fs';
import path from 'node:path';

const NO_CACHE = new Set(['index.html', 'sw.js', 'manifest.webmanifest', 'registerSW.js', 'version.json']);

/** @param {string} appDir */
export function staticApp(appDir) {
  const index = path.join(appDir, 'index.html');
  const serve = express.static(appDir, {
    index: false,
    setHeaders(res, file) {
      const rel = path.relative(appDir, file).split(path.sep).join('/');
      if (rel.startsWith('_app/immutable/')) res.setHeader('Cache-Control', 'public, max-age=31536000, immutable');
      else if (NO_CACHE.has(rel) || rel.startsWith('workbox-')) res.setHeader('Cache-Control', 'no-cache');
      else res.setHeader('Cache-Control', 'public, max-age=3600');
    },
  });
  /** @type {import('express').RequestHandler} */
  const fallback = (req, res, next) => {
    if (req.method !== 'GET' && req.method !== 'HEAD') return next();
    if (req.path.startsWith('/api/') || req.path === '/ros') return next();
    if (!fs.existsSync(index)) return res.status(503).type('text').send('The app is not built: run npm start (or npm run build -w app).');
    res.setHeader('Cache-Control', 'no-cache');
    res.sendFile(index);
  };
  return [serve, fallback];
}
