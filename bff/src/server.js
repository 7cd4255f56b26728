// The BFF process: HTTP (loopback stays on HTTP; other hosts are redirected to HTTPS), HTTPS with the local
// CA's certificate (or a user-provided one), and the /ros upgrade on both. Exits 2 with a clear message on a bad
// cell file or an unsafe users file.
import http from 'node:http';
import https from 'node:https';
import express from 'express';
import { readEnv } from './core/config/env.js';
import { createBff, StartupError } from './app.js';
import { CellConfigError } from './core/config/cell.js';
import { ensureCertificates, tlsRoutes, httpsRedirect, httpsUrlFor, isLoopback } from './core/tls/index.js';

const env = readEnv();
const log = (m) => console.log(`[bff] ${m}`);
let bff;
let tls;
let phases = '';
const tlsOpts = { dataDir: env.dataDir, userCert: env.tlsCert || undefined, userKey: env.tlsKey || undefined };
try {
  // (The phases are logged with the start time: a restarted BFF must be back quickly for a lease holder.)
  const t0 = process.uptime();
  tls = ensureCertificates(tlsOpts);
  const t1 = process.uptime();
  bff = await createBff(env, { log });
  phases = `modules ${t0.toFixed(2)} s, certificates ${(t1 - t0).toFixed(2)} s, the rest ${(process.uptime() - t1).toFixed(2)} s`;
} catch (e) {
  if (e instanceof CellConfigError || e instanceof StartupError || e?.name === 'TlsError') {
    console.error(e.message);
    process.exit(2);
  }
  throw e;
}
if (bff.initial) {
  log(`first start: created users ${bff.initial.users.map((u) => `${u.username}/${u.password}`).join(', ')}`);
  log(`(also written once to ${bff.initial.file}, mode 0600)`);
}

const front = express();
front.disable('x-powered-by');
front.use(httpsRedirect({ tlsPort: env.tlsPort }));
front.use(tlsRoutes({ caCertPem: tls.caCertPem, fingerprint: tls.caFingerprint || tls.fingerprint, httpsUrl: (req) => httpsUrlFor(req, env.tlsPort) }));
front.use(bff.app);

const server = http.createServer(front);
const secure = https.createServer({ key: tls.key, cert: tls.cert }, front);
const onUpgrade = (req, socket, head) => {
  const { pathname } = new URL(req.url, 'http://x');
  // On plain HTTP only loopback may open /ros; phones use wss.
  if (pathname === '/ros' && (/** @type {any} */ (req.socket).encrypted || isLoopback(req.socket.remoteAddress))) bff.relay.handleUpgrade(req, socket, head);
  else socket.end('HTTP/1.1 404 Not Found\r\nConnection: close\r\n\r\n');
};
server.on('upgrade', onUpgrade);
secure.on('upgrade', onUpgrade);
server.listen(env.port, env.host, () => {
  bff.lease.listening();
  log(`listening on http://${env.host}:${env.port} (started in ${process.uptime().toFixed(2)} s: ${phases})`);
});
secure.listen(env.tlsPort, env.host, () => log(`listening on https://${env.host}:${env.tlsPort} (trust page: /trust, CA: /ca.crt)`));
if (tls.source === 'generated') {
  setInterval(() => {
    const t = ensureCertificates(tlsOpts);
    if (t.renewed) secure.setSecureContext({ key: t.key, cert: t.cert });
  }, 24 * 3600e3).unref();
}

function shutdown() {
  bff.close();
  let open = 2;
  const done = () => { if (--open === 0) process.exit(0); };
  server.close(done);
  secure.close(done);
  server.closeAllConnections();
  secure.closeAllConnections();
  setTimeout(() => process.exit(0), 1500).unref();
}
process.on('SIGINT', shutdown);
process.on('SIGTERM', shutdown);
