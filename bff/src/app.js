// Builds the BFF from the core and the feature list; server.js gives it sockets. Tests build it the same way.
import fs from 'node:fs';
import path from 'node:path';
import express from 'express';
import { loadCell } from './core/config/cell.js';
import { UserStore, ensureInitialUsers } from './core/auth/users.js';
import { TokenService, RevocationList, loadOrCreateKey } from './core/auth/tokens.js';
import { sessionOf, setSessionCookie } from './core/auth/session.js';
import { LoginThrottle } from './core/auth/throttle.js';
import { authRoutes } from './core/auth/routes.js';
import { AuditLog } from './core/audit/audit-log.js';
import { ControlLease } from './core/control/lease.js';
import { LeaseFile } from './core/control/lease-file.js';
import { AwakeClock } from './core/control/awake-clock.js';
import { controlRoutes } from './core/control/routes.js';
import { configFor } from './core/access/pages.js';
import { grantsFor, motionNames, argumentChecks, stampedTopics } from './core/access/grants.js';
import { RosHealth } from './core/ros/health.js';
import { RosRelay } from './core/ros/relay.js';
import { createOpGuard } from './core/ros/op-guard.js';
import { requireSession, requirePage } from './core/http/guards.js';
import { buildOpenApi, validateRequests, methodNotAllowed, STATE_CHANGING } from './core/http/openapi.js';
import { errorBody, httpError } from './core/http/errors.js';
import { staticApp, contentSecurityPolicy } from './core/http/static.js';
import { FEATURES } from './features/index.js';

export const VERSION = '0.1.0';

export class StartupError extends Error {}

/**
 * @param {import('./core/config/env.js').Env} env
 * @param {{log?: (m: string) => void, throttle?: LoginThrottle, features?: import('./core/features/feature.js').Feature[],
 *   startedAt?: number}} [opts]
 *   features: the feature list (tests add fixture features); startedAt: when this BFF started (ms since the epoch;
 *   the process's start by default), for a control lease carried over a restart
 */
export async function createBff(env, { log = (m) => console.log(m), throttle = new LoginThrottle(), features = FEATURES, startedAt = performance.timeOrigin } = {}) {
  const cell = loadCell(env.cellConfig, features);
  fs.mkdirSync(env.dataDir, { recursive: true, mode: 0o700 });
  const users = new UserStore(env.usersFile);
  const initial = await ensureInitialUsers(users, env.dataDir, Object.keys(cell.roles));
  // Like the paper's immutable users file: only an administrator on the robot PC changes users (the CLI).
  const mode = fs.statSync(env.usersFile).mode;
  if (mode & 0o022) throw new StartupError(`${env.usersFile} is group- or world-writable (mode ${(mode & 0o777).toString(8)}); run: chmod 600 ${env.usersFile}`);

  const tokens = new TokenService({
    key: loadOrCreateKey(env.dataDir), ttlS: env.tokenTtlS, revoked: new RevocationList(path.join(env.dataDir, 'revoked.json')),
  });
  const audit = new AuditLog({ dir: env.dataDir });
  for (const r of audit.repairs) log(`audit log repaired at start: ${r.op} ${r.target}${r.detail ? ` (${r.detail})` : ''}`);
  const leaseFile = new LeaseFile(path.join(env.dataDir, 'control-lease.json'), log);
  const awake = new AwakeClock();
  const lease = new ControlLease({
    awake: () => awake.now(),
    timeoutMs: (cell.control?.heartbeat_timeout_s ?? 2) * 1000,
    onChange: (event, h, by) => audit.record({
      user: (by || h)?.username ?? null, role: (by || h)?.role ?? null, ip: null, op: `control.${event}`,
      target: h?.username, outcome: 'ok',
    }),
    persist: (saved) => leaseFile.write(saved),
  });
  lease.resume(leaseFile.read(), startedAt);
  const rosHealth = new RosHealth({ masterUri: env.rosMasterUri, rosbridgePort: env.rosbridgePort });
  const started = Date.now();
  /** @type {Record<string, () => object>} what features add to the health report (e.g. the plant broker link) */
  const healthParts = {};
  /** @type {(() => void)[]} the features' background services, stopped on close */
  const closers = [];
  const healthReport = async () => ({
    status: 'ok', version: VERSION, uptime_s: (Date.now() - started) / 1000, ros: await rosHealth.get(),
    ...Object.fromEntries(Object.entries(healthParts).map(([k, fn]) => [k, fn()])),
  });
  const authenticate = (req) => sessionOf(req, tokens, users);
  const grants = new Map(Object.keys(cell.roles).map((role) => [role, grantsFor(cell, features, role)]));
  const openapi = buildOpenApi(features);

  const relay = new RosRelay({
    upstreamUrl: `ws://127.0.0.1:${env.rosbridgePort}`,
    authenticate,
    checkOrigin: sameOrigin,
    guard: createOpGuard({
      grantsOf: (role) => grants.get(role), motion: motionNames(cell, features), stamped: stampedTopics(cell, features), lease, audit, checkArgs: argumentChecks(cell, features),
    }),
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
  // A documented path asked with a method the document does not declare there: 405 with Allow (OPTIONS: 204),
  // before anything reads the body.
  app.use(methodNotAllowed(openapi));
  // JSON bodies of state-changing requests only (a GET's body is ignored, never a reason to fail).
  app.use('/api', express.json({ limit: '64kb', type: (req) => STATE_CHANGING(req.method) && Boolean(/** @type {express.Request} */ (req).is('application/json')) }));
  app.use('/api', (req, res, next) => {
    // State-changing requests must come from our own origin (the cookie is SameSite=Strict too).
    if (req.method !== 'GET' && req.method !== 'HEAD' && !sameOrigin(req)) return res.status(403).json(errorBody('cross-origin request refused', 'request.cross_origin'));
    req.session = authenticate(req);
    // Sliding session: a token past half its life is replaced while the app is in use.
    if (req.session && tokens.needsRenewal(req.session.claims) && req.path !== '/auth/logout') {
      setSessionCookie(res, tokens.issue(req.session, req.session.sid), req.secure, tokens.ttlS);
    }
    res.setHeader('Cache-Control', 'no-store');
    next();
  });
  // The features' bodies are validated after their page guard (below); the core's here.
  const featurePaths = new Set(features.flatMap((f) => Object.keys(f.openapi || {})));
  app.use(validateRequests(openapi, { include: (p) => !featurePaths.has(p), audit }));
  app.get('/api/health', async (req, res) => res.json(await healthReport()));
  app.get('/api/openapi.json', (req, res) => res.json(openapi));
  app.use(authRoutes({
    users, tokens, throttle, audit,
    onLogout: (s) => {
      lease.release(s, 'released-on-logout');
      relay.closeWhere((x) => x.sid === s.sid, 'logged out');
    },
  }));
  app.get('/api/config', requireSession, (req, res) => res.json(configFor(cell, features, req.session.role)));
  // Roles whose commands include a feature with motion commands (the features that need the lease).
  const movers = new Set(features.filter((f) => f.motion).map((f) => f.id));
  const mayControl = (/** @type {string} */ role) => (cell.roles[role]?.commands ?? []).some((c) => movers.has(c));
  app.use(controlRoutes({ lease, cell, mayControl }));
  for (const f of features) {
    if (!f.routes) continue;
    app.use(f.routes({
      cell, section: cell[f.id], cellFile: env.cellConfig, env, users, audit, healthReport, log,
      onClose: (fn) => { closers.push(fn); }, addHealth: (key, fn) => { healthParts[key] = fn; },
      guard: [requireSession, requirePage(cell, f.id), validateRequests(openapi, { include: (p) => featurePaths.has(p), audit })],
    }));
  }
  app.use('/api', (req, res) => res.status(404).json({ error: `no such API: ${req.method} ${req.originalUrl.slice(0, 300)}` }));
  app.use(...staticApp(env.appDir));
  // Client errors raised below the handlers (bad percent-encoding, body parser, multipart): their 4xx and a clear
  // message. 500 only for real failures, logged, never with a stack trace in the answer.
  app.use((err, req, res, next) => {
    if (res.headersSent) return next(err);
    const e = httpError(err);
    if (!e.clientError) log(`error on ${req.method} ${req.originalUrl}: ${err?.stack || err}`);
    res.status(e.status).json(e.code ? errorBody(e.message, e.code, e.params) : { error: e.message });
  });

  return { app, relay, cell, features, grants, openapi, users, tokens, audit, lease, initial, close: () => { relay.close(); awake.stop(); for (const c of closers) c(); } };
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
