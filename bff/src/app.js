// Builds the BFF from its parts; server.js gives it sockets. Tests build it the same way.
import fs from 'node:fs';
import path from 'node:path';
import express from 'express';
import { loadCell } from './config/cell.js';
import { UserStore, ensureInitialUsers } from './auth/users.js';
import { TokenService, RevocationList, loadOrCreateKey } from './auth/tokens.js';
import { sessionOf } from './auth/session.js';
import { RosHealth } from './ros/health.js';
import { RosRelay } from './ros/relay.js';
import { authRoutes } from './routes/auth.js';
import { cellRoutes } from './routes/cell.js';
import { openapi, validateRequests } from './http/openapi.js';
import { staticApp } from './http/static.js';

export const VERSION = '0.1.0';

/**
 * @param {import('./config/env.js').Env} env
 * @param {{log?: (m: string) => void}} [opts]
 */
export async function createBff(env, { log = (m) => console.log(`[bff] ${m}`) } = {}) {
  const cell = loadCell(env.cellConfig);
  fs.mkdirSync(env.dataDir, { recursive: true, mode: 0o700 });
  const users = new UserStore(env.usersFile);
  const initial = await ensureInitialUsers(users, env.dataDir);
  const tokens = new TokenService({
    key: loadOrCreateKey(env.dataDir), ttlS: env.tokenTtlS, revoked: new RevocationList(path.join(env.dataDir, 'revoked.json')),
  });
  const rosHealth = new RosHealth({ masterUri: env.rosMasterUri, rosbridgePort: env.rosbridgePort });
  const started = Date.now();
  const healthReport = async () => ({ status: 'ok', version: VERSION, uptime_s: (Date.now() - started) / 1000, ros: await rosHealth.get() });
  const authenticate = (req) => sessionOf(req, tokens, users);

  const relay = new RosRelay({
    upstreamUrl: `ws://127.0.0.1:${env.rosbridgePort}`,
    authenticate,
    checkOrigin: sameOrigin,
    isValid: (s) => !tokens.revoked.has(s.claims.jti) && users.get(s.username)?.role === s.role,
    log,
  });

  const app = express();
  app.disable('x-powered-by');
  app.set('trust proxy', false);
  app.use((req, res, next) => {
    res.setHeader('X-Content-Type-Options', 'nosniff');
    res.setHeader('Referrer-Policy', 'no-referrer');
    res.setHeader('X-Frame-Options', 'DENY');
    res.setHeader('Content-Security-Policy', "frame-ancestors 'none'");
    next();
  });
  app.use('/api', express.json({ limit: '64kb' }));
  app.use('/api', (req, res, next) => {
    // State-changing requests must come from our own origin (the cookie is SameSite=Strict too).
    if (req.method !== 'GET' && req.method !== 'HEAD' && !sameOrigin(req)) return res.status(403).json({ error: 'cross-origin request refused' });
    req.session = authenticate(req);
    res.setHeader('Cache-Control', 'no-store');
    next();
  });
  app.use(validateRequests());
  app.get('/api/health', async (req, res) => res.json(await healthReport()));
  app.get('/api/openapi.json', (req, res) => res.json(openapi));
  app.use(authRoutes({
    users, tokens, log,
    onLogout: (s) => relay.closeWhere((x) => x.claims.jti === s.claims.jti, 'logged out'),
  }));
  app.use(cellRoutes({ cell, cellFile: env.cellConfig, users, healthReport }));
  app.use('/api', (req, res) => res.status(404).json({ error: `no such API: ${req.method} ${req.originalUrl}` }));
  app.use(...staticApp(env.appDir));
  // Malformed JSON and other client errors: a clear message, never a stack trace.
  app.use((err, req, res, next) => {
    if (res.headersSent) return next(err);
    const status = err.status || err.statusCode || 500;
    if (status >= 500) log(`error on ${req.method} ${req.originalUrl}: ${err.stack || err}`);
    res.status(status).json({ error: status >= 500 ? 'internal error' : err.type === 'entity.parse.failed' ? 'malformed JSON body' : err.message });
  });

  return { app, relay, cell, users, tokens, initial, close: () => relay.close() };
}

/** Origin (when the browser sends one) must name the host the request was sent to. @param {import('node:http').IncomingMessage} req */
export function sameOrigin(req) {
  const origin = req.headers.origin;
  if (!origin) return true;
  try {
    return new URL(origin).host === req.headers.host;
  } catch {
    return false;
  }
}
