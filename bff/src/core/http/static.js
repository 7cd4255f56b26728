// Serves the built PWA: hashed assets cached forever, the shell and the service worker never cached,
// and index.html for any other non-API path (the SPA router takes it from there).
import express from 'express';
import crypto from 'node:crypto';
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

/**
 * Content-Security-Policy for the app: only our own origin, plus the hashes of the shell's inline scripts
 * (SvelteKit's bootstrap), read from the built index.html so no 'unsafe-inline' is needed for scripts.
 * @param {string} appDir
 */
export function contentSecurityPolicy(appDir) {
  let hashes = [];
  try {
    const html = fs.readFileSync(path.join(appDir, 'index.html'), 'utf8');
    hashes = [...html.matchAll(/<script(?![^>]*\bsrc=)[^>]*>([\s\S]*?)<\/script>/g)]
      .map((m) => `'sha256-${crypto.createHash('sha256').update(m[1]).digest('base64')}'`);
  } catch { /* not built: nothing inline to allow */ }
  return [
    "default-src 'self'", `script-src 'self' ${hashes.join(' ')}`.trim(),
    // Svelte sets style attributes for layout and transitions.
    "style-src 'self' 'unsafe-inline'", "img-src 'self' data: blob:", "connect-src 'self'", "worker-src 'self'",
    "manifest-src 'self'", "font-src 'self'", "object-src 'none'", "base-uri 'self'", "form-action 'self'", "frame-ancestors 'none'",
  ].join('; ');
}
