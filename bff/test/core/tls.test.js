import { test } from 'node:test';
import assert from 'node:assert/strict';
import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import https from 'node:https';
import path from 'node:path';
import express from 'express';
import { tempDir } from '../helpers.js';
import { ensureCertificates, tlsRoutes, httpsRedirect, httpsUrlFor, isLoopback } from '../../src/core/tls/index.js';

const base = { hostnames: ['robot-pc'], addresses: ['192.0.2.10'] };

/** GET over HTTPS trusting only `ca`. */
function httpsGet(port, ca, servername) {
  return new Promise((resolve, reject) => {
    const req = https.request({ host: '127.0.0.1', port, path: '/', ca, servername, method: 'GET' }, (res) => {
      let body = '';
      res.on('data', (c) => (body += c));
      res.on('end', () => resolve({ status: res.statusCode, body }));
    });
    req.on('error', reject);
    req.end();
  });
}

async function listen(server) {
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return server.address().port;
}

test('local CA and server certificate: chain, SANs, key modes, reuse, regeneration', async () => {
  const dataDir = tempDir();
  const a = ensureCertificates({ dataDir, ...base });
  assert.equal(a.source, 'generated');
  assert.ok(a.caCertPem);
  const ca = new crypto.X509Certificate(a.caCertPem);
  const srv = new crypto.X509Certificate(a.cert);
  assert.ok(ca.ca, 'CA certificate has CA:TRUE');
  assert.ok(srv.checkIssued(ca), 'server certificate issued by the CA');
  assert.ok(srv.verify(ca.publicKey), 'server certificate signature verifies with the CA key');
  assert.ok(ca.verify(ca.publicKey), 'CA is self-signed');
  assert.ok(srv.checkPrivateKey(crypto.createPrivateKey(a.key)));
  const san = srv.subjectAltName;
  for (const n of ['DNS:localhost', 'DNS:robot-pc', 'IP Address:127.0.0.1', 'IP Address:192.0.2.10']) assert.ok(san.includes(n), `${n} in ${san}`);
  assert.match(san, /IP Address:(0:0:0:0:0:0:0:1|::1)/);
  assert.deepEqual(a.names, ['localhost', 'robot-pc', '127.0.0.1', '192.0.2.10', '::1']);
  // CA ~10 years, server below Apple's 825 days.
  const days = (x) => (new Date(x.validTo) - new Date(x.validFrom)) / 86400000;
  assert.ok(days(ca) > 3640 && days(srv) <= 825);

  const dir = path.join(dataDir, 'tls');
  for (const f of ['ca.key', 'server.key']) assert.equal(fs.statSync(path.join(dir, f)).mode & 0o777, 0o600, f);
  assert.equal(fs.statSync(dir).mode & 0o777, 0o700);

  const b = ensureCertificates({ dataDir, ...base });
  assert.equal(b.fingerprint, a.fingerprint, 'second start reuses the server certificate');
  assert.equal(b.caFingerprint, a.caFingerprint);
  assert.equal(b.renewed, false);

  const c = ensureCertificates({ dataDir, hostnames: ['robot-pc'], addresses: ['192.0.2.11'] });
  assert.notEqual(c.fingerprint, a.fingerprint, 'new address: new server certificate');
  assert.equal(c.caFingerprint, a.caFingerprint, 'CA kept');
  assert.equal(c.caCertPem, a.caCertPem);
  const c2 = new crypto.X509Certificate(c.cert);
  assert.ok(c2.checkIssued(ca) && c2.verify(ca.publicKey));
  assert.ok(c2.subjectAltName.includes('IP Address:192.0.2.11') && !c2.subjectAltName.includes('192.0.2.10'));
  // A new key takes seconds on a busy robot PC (a restarted BFF must be back within the lease's timeout): kept.
  assert.equal(c.key, a.key, 'new address: the server key is kept, certified again');
  assert.ok(c2.checkPrivateKey(crypto.createPrivateKey(c.key)));

  // Near expiry: a start 380 days later renews the server certificate, CA kept.
  const later = new Date(Date.now() + 380 * 86400000);
  const d = ensureCertificates({ dataDir, hostnames: ['robot-pc'], addresses: ['192.0.2.11'], now: later });
  assert.notEqual(d.fingerprint, c.fingerprint);
  assert.equal(d.caFingerprint, a.caFingerprint);
});

test('default names come from os.hostname() and the network interfaces', () => {
  const dataDir = tempDir();
  const t = ensureCertificates({ dataDir });
  assert.ok(t.names.includes('localhost') && t.names.includes('127.0.0.1') && t.names.includes('::1'));
});

test('HTTPS server with the generated certificate answers a client that trusts only the CA', async () => {
  const dataDir = tempDir();
  const t = ensureCertificates({ dataDir, ...base });
  const server = https.createServer({ key: t.key, cert: t.cert }, (req, res) => res.end('secure hello'));
  const port = await listen(server);
  try {
    const res = await httpsGet(port, t.caCertPem);
    assert.equal(res.status, 200);
    assert.equal(res.body, 'secure hello');
    const res2 = await httpsGet(port, t.caCertPem, 'localhost');
    assert.equal(res2.body, 'secure hello');
    // A client trusting another CA refuses the connection.
    const other = ensureCertificates({ dataDir: tempDir(), ...base });
    await assert.rejects(httpsGet(port, other.caCertPem));
  } finally {
    server.closeAllConnections();
    await new Promise((r) => server.close(r));
  }
});

test('user-provided certificate and key are used as given, no CA', async () => {
  const own = ensureCertificates({ dataDir: tempDir(), ...base }); // any valid pair stands in for an IT-issued one
  const dir = tempDir();
  const certFile = path.join(dir, 'my.crt');
  const keyFile = path.join(dir, 'my.key');
  fs.writeFileSync(certFile, own.cert);
  fs.writeFileSync(keyFile, own.key);
  const dataDir = tempDir();
  const t = ensureCertificates({ dataDir, userCert: certFile, userKey: keyFile });
  assert.equal(t.source, 'user');
  assert.equal(t.cert, own.cert);
  assert.equal(t.key, own.key);
  assert.equal(t.caCertPem, null);
  assert.equal(t.fingerprint, own.fingerprint);
  assert.ok(t.names.includes('localhost'));
  assert.equal(fs.existsSync(path.join(dataDir, 'tls', 'ca.key')), false, 'no CA created');
  // Mismatched pair or only one of the two: a clear error.
  const other = ensureCertificates({ dataDir: tempDir(), ...base });
  fs.writeFileSync(keyFile, other.key);
  assert.throws(() => ensureCertificates({ dataDir, userCert: certFile, userKey: keyFile }), /does not belong/);
  assert.throws(() => ensureCertificates({ dataDir, userCert: certFile }), /together/);

  // /ca.crt is 404 then; /trust still works.
  const app = express().use(tlsRoutes({ caCertPem: null, httpsUrl: 'https://robot-pc:8443/', fingerprint: t.fingerprint }));
  const server = http.createServer(app);
  const port = await listen(server);
  try {
    assert.equal((await fetch(`http://127.0.0.1:${port}/ca.crt`)).status, 404);
    const page = await (await fetch(`http://127.0.0.1:${port}/trust`)).text();
    assert.ok(page.includes(t.fingerprint));
  } finally {
    await new Promise((r) => server.close(r));
  }
});

test('/ca.crt and /trust over plain HTTP without a session', async () => {
  const t = ensureCertificates({ dataDir: tempDir(), ...base });
  const app = express().use(tlsRoutes({ caCertPem: t.caCertPem, httpsUrl: (req) => httpsUrlFor(req, 8443) }));
  const server = http.createServer(app);
  const port = await listen(server);
  try {
    const ca = await fetch(`http://127.0.0.1:${port}/ca.crt`);
    assert.equal(ca.status, 200);
    assert.equal(ca.headers.get('content-type').split(';')[0], 'application/x-x509-ca-cert');
    assert.equal(await ca.text(), t.caCertPem);

    const res = await fetch(`http://127.0.0.1:${port}/trust`);
    assert.equal(res.status, 200);
    assert.match(res.headers.get('content-type'), /text\/html/);
    const csp = res.headers.get('content-security-policy');
    assert.match(csp, /default-src 'none'/);
    assert.doesNotMatch(csp, /script-src|unsafe-inline/);
    const html = await res.text();
    assert.ok(html.includes('https://127.0.0.1:8443/'), 'shows the HTTPS URL for the host used');
    assert.ok(html.includes('<svg'), 'QR code inline');
    assert.ok(html.includes('href="/ca.crt"'));
    assert.ok(html.includes(t.caFingerprint), 'CA fingerprint shown');
    assert.ok(html.includes('Encryption &amp; credentials') && html.includes('Certificate Trust Settings'));
    assert.doesNotMatch(html, /<script|https?:\/\/(?!127\.0\.0\.1:8443|www\.w3\.org)/, 'no scripts, no external assets');
    // The style hash in the CSP matches the <style> element.
    const style = /<style>([\s\S]*?)<\/style>/.exec(html)[1];
    assert.ok(csp.includes(`sha256-${crypto.createHash('sha256').update(style).digest('base64')}`));
    // A Host header naming the machine is reflected; a malformed one is not.
    assert.equal(httpsUrlFor({ headers: { host: 'robot-pc.local:8080' } }, 8443), 'https://robot-pc.local:8443/');
    assert.equal(httpsUrlFor({ headers: { host: '[fd00::2]:8080' } }, 8443), 'https://[fd00::2]:8443/');
    assert.equal(httpsUrlFor({ headers: { host: 'evil.com/"><x' } }, 8443), null);
  } finally {
    await new Promise((r) => server.close(r));
  }
});

/** Calls the middleware with a fake request; returns {next: boolean, status, location}. */
function runRedirect(mw, { remoteAddress, url = '/', host = 'robot-pc:8080' }) {
  const out = { next: false, status: null, location: null, body: null };
  const req = { socket: { remoteAddress }, headers: { host }, originalUrl: url, path: url.split('?')[0] };
  const res = {
    redirect(status, location) { out.status = status; out.location = location; },
    status(s) { out.status = s; return this; },
    type() { return this; },
    send(b) { out.body = b; },
  };
  mw(req, res, () => { out.next = true; });
  return out;
}

test('httpsRedirect: non-loopback clients go to HTTPS, loopback and bootstrap paths stay on HTTP', async () => {
  const mw = httpsRedirect({ tlsPort: 8443 });
  let r = runRedirect(mw, { remoteAddress: '192.0.2.50', url: '/process?x=1' });
  assert.deepEqual([r.next, r.status, r.location], [false, 308, 'https://robot-pc:8443/process?x=1']);
  r = runRedirect(mw, { remoteAddress: '::ffff:192.0.2.50', url: '/', host: '192.0.2.10:8080' });
  assert.equal(r.location, 'https://192.0.2.10:8443/');
  r = runRedirect(mw, { remoteAddress: 'fd00::9', url: '/api/config', host: '[fd00::2]:8080' });
  assert.equal(r.location, 'https://[fd00::2]:8443/api/config');
  for (const p of ['/ca.crt', '/trust', '/api/health']) assert.ok(runRedirect(mw, { remoteAddress: '192.0.2.50', url: p }).next, p);
  for (const a of ['127.0.0.1', '127.1.2.3', '::1', '::ffff:127.0.0.1']) assert.ok(runRedirect(mw, { remoteAddress: a, url: '/x' }).next, a);
  assert.equal(runRedirect(mw, { remoteAddress: '192.0.2.50', host: 'a@b/c' }).status, 400);
  assert.equal(runRedirect(mw, { remoteAddress: '192.0.2.50', url: '//evil.example/x' }).location, 'https://robot-pc:8443/');
  const tls = runRedirect(mw, { remoteAddress: '192.0.2.50', url: '/x' });
  assert.equal(tls.status, 308);
  const viaTls = { next: false };
  mw({ socket: { remoteAddress: '192.0.2.50', encrypted: true }, headers: { host: 'robot-pc:8443' }, originalUrl: '/x', path: '/x' }, {}, () => { viaTls.next = true; });
  assert.ok(viaTls.next, 'requests over TLS pass (one app for both servers)');
  assert.ok(!isLoopback('128.0.0.1') && !isLoopback(undefined) && !isLoopback('::ffff:10.0.0.1'));

  // Against a real server: loopback requests pass through.
  const app = express().use(httpsRedirect({ tlsPort: 8443 })).get('/x', (req, res) => res.send('plain'));
  const server = http.createServer(app);
  const port = await listen(server);
  try {
    assert.equal(await (await fetch(`http://127.0.0.1:${port}/x`)).text(), 'plain');
  } finally {
    await new Promise((r) => server.close(r));
  }
});
