// Builds the BFF from its parts; server.js gives it sockets. Tests build it the same way.
import fs from 'node:fs';
import path from 'node:path';
import express from 'express';
import { loadCell } from './config/cell.js';
import { UserStore, ensureInitialUsers } from './auth/users.js';
import { TokenService, RevocationList, loadOrCreateKey } from './auth/tokens.js';
import { sessionOf, setSessionCookie } from './auth/session.js';
import { LoginThrottle } from './auth/throttle.js';
import { AuditLog } from './audit/audit-log.js';
import { ControlLease } from './control/lease.js';
import { RosHealth } from './ros/health.js';
import { RosRelay } from './ros/relay.js';
import { createOpGuard } from './ros/op-guard.js';
import { authRoutes } from './routes/auth.js';
import { cellRoutes, requireSession, requirePage } from './routes/cell.js';
import { DatabaseFiles, databaseRoutes, resolveUsbRoots } from './files/index.js';
import { controlRoutes } from './routes/control.js';
import { auditRoutes } from './routes/audit.js';
import { openapi, validateRequests } from './http/openapi.js';
import { staticApp, contentSecurityPolicy } from './http/static.js';

export const VERSION = '0.1.0';

export class StartupError extends Error {}

/**
 * @param {import('./config/env.js').Env} env
 * @param {{log?: (m: string) => void, throttle?: LoginThrottle}} [opts]
 */
export async function createBff(env, { log = (m) => console.log(m), throttle = new LoginThrottle() } = {}) {
  const cell = loadCell(env.cellConfig);
  fs.mkdirSync(env.dataDir, { recursive: true, mode: 0o700 });
  const users = new UserStore(env.usersFile);
  const initial = await ensureInitialUsers(users, env.dataDir);
  // Like the paper's immutable users file: only an administrator on the robot PC changes users (the CLI).
  const mode = fs.statSync(env.usersFile).mode;
  if (mode & 0o022) throw new StartupError(`${env.usersFile} is group- or world-writable (mode ${(mode & 0o777).toString(8)}); run: chmod 600 ${env.usersFile}`);

  const tokens = new TokenService({
    key: loadOrCreateKey(env.dataDir), ttlS: env.tokenTtlS, revoked: new RevocationList(path.join(env.dataDir, 'revoked.json')),
  });
  const audit = new AuditLog({ dir: env.dataDir });
  const lease = new ControlLease({
    timeoutMs: (cell.control?.heartbeat_timeout_s ?? 2) * 1000,
    onChange: (event, h, by) => audit.record({
      user: (by || h)?.username ?? null, role: (by || h)?.role ?? null, ip: null, op: `control.${event}`,
      target: h?.username, outcome: 'ok',
    }),
  });
  const database = new DatabaseFiles({ cell, dataDir: env.dataDir, usbRoots: resolveUsbRoots(env.usbRoots, cell), audit });
  const rosHealth = new RosHealth({ masterUri: env.rosMasterUri, rosbridgePort: env.rosbridgePort });
  const started = Date.now();
  const healthReport = async () => ({ status: 'ok', version: VERSION, uptime_s: (Date.now() - started) / 1000, ros: await rosHealth.get() });
  const authenticate = (req) => sessionOf(req, tokens, users);

  const relay = new RosRelay({
    upstreamUrl: `ws://127.0.0.1:${env.rosbridgePort}`,
    authenticate,
    checkOrigin: sameOrigin,
    guard: createOpGuard({ cell, lease, audit }),
    isValid: (s) => tokens.sessionAlive(s.claims) && users.get(s.username)?.role === s.role,
    // A lease holder that disconnects gives control back.
    onClose: (s, stillOpen) => { if (stillOpen === 0) lease.release(s, 'released-on-disconnect'); },
    log,
  });

  const csp = contentSecurityPolicy(env.appDir);
  const app = express();
  app.disable('x-powered-by');
  app.use((req, res, next) => {
    res.setHeader('X-Content-Type-Options', 'nosniff');
    res.setHeader('Referrer-Policy', 'no-referrer');
    res.setHeader('X-Frame-Options', 'DENY');
    res.setHeader('Content-Security-Policy', csp);
    next();
  });
  app.use('/api', express.json({ limit: '64kb' }));
  app.use('/api', (req, res, next) => {
    // State-changing requests must come from our own origin (the cookie is SameSite=Strict too).
    if (req.method !== 'GET' && req.method !== 'HEAD' && !sameOrigin(req)) return res.status(403).json({ error: 'cross-origin request refused' });
    req.session = authenticate(req);
    // Sliding session: a token past half its life is replaced while the app is in use.
    if (req.session && tokens.needsRenewal(req.session.claims) && req.path !== '/auth/logout') {
      setSessionCookie(res, tokens.issue(req.session, req.session.sid), req.secure, tokens.ttlS);
    }
    res.setHeader('Cache-Control', 'no-store');
    next();
  });
  app.use(validateRequests());
  app.get('/api/health', async (req, res) => res.json(await healthReport()));
  app.get('/api/openapi.json', (req, res) => res.json(openapi));
  app.use(authRoutes({
    users, tokens, throttle, audit,
    onLogout: (s) => {
      lease.release(s, 'released-on-logout');
      relay.closeWhere((x) => x.sid === s.sid, 'logged out');
    },
  }));
  app.use(cellRoutes({ cell, cellFile: env.cellConfig, users, healthReport }));
  app.use(controlRoutes({ lease }));
  app.use(auditRoutes({ audit, cell }));
  app.use(databaseRoutes({ service: database, requireSession, requirePage, log }));
  app.use('/api', (req, res) => res.status(404).json({ error: `no such API: ${req.method} ${req.originalUrl}` }));
  app.use(...staticApp(env.appDir));
  // Malformed JSON and other client errors: a clear message, never a stack trace.
  app.use((err, req, res, next) => {
    if (res.headersSent) return next(err);
    const status = err.status || err.statusCode || 500;
    if (status >= 500) log(`error on ${req.method} ${req.originalUrl}: ${err.stack || err}`);
    res.status(status).json({ error: status >= 500 ? 'internal error' : err.type === 'entity.parse.failed' ? 'malformed JSON body' : err.message });
  });

  return { app, relay, cell, users, tokens, audit, lease, database, initial, close: () => relay.close() };
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
