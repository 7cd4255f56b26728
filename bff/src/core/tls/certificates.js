// A local CA and a server certificate for HTTPS on the shop floor (phones need a secure context for the PWA).
// Files in DATA_DIR/tls/: ca.key (0600), ca.crt, server.key (0600), server.crt, server.json (the names it was issued for).
// X.509 is built with node-forge; keys come from Node's crypto. No shell commands.
import crypto from 'node:crypto';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import forge from 'node-forge';
import { writeFileAtomic } from '../auth/atomic-file.js';

const DAY_MS = 24 * 3600 * 1000;
/** CA lifetime. */
export const CA_DAYS = 3650;
/** Server certificate lifetime: below Apple's 825-day limit for TLS server certificates. */
export const SERVER_DAYS = 397;
/** A server certificate with less than this left is renewed at start. */
export const RENEW_BEFORE_DAYS = 30;

/**
 * @typedef {object} TlsMaterial
 * @property {string} key server private key (PEM)
 * @property {string} cert server certificate (PEM; for a user certificate, the file as given, chain included)
 * @property {string|null} caCertPem our local CA certificate (PEM), null when a user certificate is used
 * @property {string[]} names DNS names and IP addresses of the server certificate
 * @property {string} fingerprint SHA-256 fingerprint of the server certificate ("AB:CD:...")
 * @property {string|null} caFingerprint SHA-256 fingerprint of the CA certificate, null with a user certificate
 * @property {'generated'|'user'} source
 * @property {boolean} renewed whether the server certificate was (re)issued by this call
 * @property {string} dir the tls directory
 */

/**
 * Create or reuse the local CA and server certificate; or load a user-provided certificate (TLS_CERT/TLS_KEY).
 * @param {{dataDir: string, hostnames?: string[], addresses?: string[], userCert?: string, userKey?: string,
 *   now?: Date}} o hostnames/addresses replace the detected ones (os.hostname(), network interfaces);
 *   'localhost', 127.0.0.1 and ::1 are always included. userCert/userKey are file paths.
 * @returns {TlsMaterial}
 */
export function ensureCertificates({ dataDir, hostnames, addresses, userCert, userKey, now = new Date() }) {
  const dir = path.join(dataDir, 'tls');
  if (userCert || userKey) return loadUserCertificate(userCert, userKey, dir);
  fs.mkdirSync(dir, { recursive: true, mode: 0o700 });
  const files = {
    caKey: path.join(dir, 'ca.key'), caCert: path.join(dir, 'ca.crt'),
    key: path.join(dir, 'server.key'), cert: path.join(dir, 'server.crt'), meta: path.join(dir, 'server.json'),
  };
  const names = certificateNames({ hostnames, addresses });

  let ca = readCa(files, now);
  let renewed = false;
  if (!ca) {
    ca = createCa(now);
    writeFileAtomic(files.caKey, ca.keyPem, 0o600);
    writeFileAtomic(files.caCert, ca.certPem, 0o644);
    renewed = true;
  }
  let server = renewed ? null : readServer(files, ca, names, now);
  if (!server) {
    // A new address (a network came up) needs a new certificate, not a new key: an RSA key takes seconds to make on
    // a busy robot PC, and a restarted BFF must be back within the control lease's heartbeat timeout.
    server = createServerCert(ca, names, now, renewed ? null : readKey(files.key));
    writeFileAtomic(files.key, server.keyPem, 0o600);
    writeFileAtomic(files.cert, server.certPem, 0o644);
    writeFileAtomic(files.meta, JSON.stringify({ names, issued: now.toISOString() }, null, 2) + '\n', 0o644);
    renewed = true;
  }
  // Files written by older versions or copied around: make sure keys are private.
  for (const f of [files.caKey, files.key]) fs.chmodSync(f, 0o600);
  return {
    key: server.keyPem, cert: server.certPem, caCertPem: ca.certPem, names,
    fingerprint: new crypto.X509Certificate(server.certPem).fingerprint256,
    caFingerprint: new crypto.X509Certificate(ca.certPem).fingerprint256,
    source: /** @type {const} */ ('generated'), renewed, dir,
  };
}

/**
 * The names a server certificate is issued for, sorted and deduplicated.
 * @param {{hostnames?: string[], addresses?: string[]}} [o]
 * @returns {string[]}
 */
export function certificateNames({ hostnames, addresses } = {}) {
  const host = os.hostname();
  const hosts = hostnames ?? [host, ...(host && !host.includes('.') ? [`${host}.local`] : [])];
  const addrs = addresses ?? Object.values(os.networkInterfaces()).flat().map((i) => i?.address).filter(Boolean);
  const dns = [...hosts, 'localhost']
    .map((h) => String(h).trim().toLowerCase())
    .filter((h) => /^[a-z0-9_]([a-z0-9_.-]{0,252})$/.test(h) && !net.isIP(h));
  const ips = [...addrs, '127.0.0.1', '::1']
    .map((a) => String(a).replace(/%.*$/, '').toLowerCase()) // drop IPv6 zone ids (fe80::1%eth0)
    .filter((a) => net.isIP(a));
  return [...new Set(dns)].sort().concat([...new Set(ips)].sort());
}

function loadUserCertificate(certFile, keyFile, dir) {
  if (!certFile || !keyFile) throw new Error('TLS_CERT and TLS_KEY must be given together');
  const cert = fs.readFileSync(certFile, 'utf8');
  const key = fs.readFileSync(keyFile, 'utf8');
  let x509;
  try {
    x509 = new crypto.X509Certificate(cert);
  } catch (e) {
    throw new Error(`TLS_CERT ${certFile} is not a PEM certificate: ${e.message}`);
  }
  let privateKey;
  try {
    privateKey = crypto.createPrivateKey(key);
  } catch (e) {
    throw new Error(`TLS_KEY ${keyFile} is not a PEM private key: ${e.message}`);
  }
  if (!x509.checkPrivateKey(privateKey)) throw new Error(`TLS_KEY ${keyFile} does not belong to TLS_CERT ${certFile}`);
  const names = (x509.subjectAltName || '').split(', ').filter(Boolean).map((s) => s.replace(/^(DNS|IP Address):/, ''));
  return { key, cert, caCertPem: null, names, fingerprint: x509.fingerprint256, caFingerprint: null, source: /** @type {const} */ ('user'), renewed: false, dir };
}

/** @returns {{keyPem: string, certPem: string, key: forge.pki.rsa.PrivateKey, cert: forge.pki.Certificate}|null} */
function readCa(files, now) {
  try {
    const keyPem = fs.readFileSync(files.caKey, 'utf8');
    const certPem = fs.readFileSync(files.caCert, 'utf8');
    const x = new crypto.X509Certificate(certPem);
    if (!x.ca || !x.checkPrivateKey(crypto.createPrivateKey(keyPem)) || new Date(x.validTo) <= now) return null;
    return { keyPem, certPem, key: forge.pki.privateKeyFromPem(keyPem), cert: forge.pki.certificateFromPem(certPem) };
  } catch {
    return null;
  }
}

/** The existing server certificate if it is for exactly these names, issued by this CA and not near expiry. */
function readServer(files, ca, names, now) {
  try {
    const keyPem = fs.readFileSync(files.key, 'utf8');
    const certPem = fs.readFileSync(files.cert, 'utf8');
    const meta = JSON.parse(fs.readFileSync(files.meta, 'utf8'));
    if (JSON.stringify(meta.names) !== JSON.stringify(names)) return null;
    const x = new crypto.X509Certificate(certPem);
    const caX = new crypto.X509Certificate(ca.certPem);
    if (!x.checkIssued(caX) || !x.verify(caX.publicKey)) return null;
    if (!x.checkPrivateKey(crypto.createPrivateKey(keyPem))) return null;
    if (new Date(x.validTo).getTime() - now.getTime() < RENEW_BEFORE_DAYS * DAY_MS) return null;
    return { keyPem, certPem };
  } catch {
    return null;
  }
}

function newKeyPair() {
  const { privateKey } = crypto.generateKeyPairSync('rsa', {
    modulusLength: 2048, privateKeyEncoding: { type: 'pkcs8', format: 'pem' }, publicKeyEncoding: { type: 'spki', format: 'pem' },
  });
  const key = forge.pki.privateKeyFromPem(privateKey);
  return { keyPem: privateKey, key, publicKey: forge.pki.setRsaPublicKey(key.n, key.e) };
}

function serialNumber() {
  const b = crypto.randomBytes(16);
  b[0] &= 0x7f; // positive
  b[0] |= 0x01; // no leading zero byte
  return b.toString('hex');
}

function createCa(now) {
  const { keyPem, key, publicKey } = newKeyPair();
  const cert = forge.pki.createCertificate();
  cert.publicKey = publicKey;
  cert.serialNumber = serialNumber();
  cert.validity.notBefore = new Date(now.getTime() - 3600 * 1000);
  cert.validity.notAfter = new Date(now.getTime() + CA_DAYS * DAY_MS);
  const attrs = [
    { name: 'commonName', value: `Robot cell local CA (${safeLabel(os.hostname())} ${now.toISOString().slice(0, 10)})` },
    { name: 'organizationName', value: 'Robot cell' },
  ];
  cert.setSubject(attrs);
  cert.setIssuer(attrs);
  cert.setExtensions([
    { name: 'basicConstraints', cA: true, pathLenConstraint: 0, critical: true },
    { name: 'keyUsage', keyCertSign: true, cRLSign: true, critical: true },
    { name: 'subjectKeyIdentifier' },
  ]);
  cert.sign(key, forge.md.sha256.create());
  return { keyPem, key, cert, certPem: forge.pki.certificateToPem(cert) };
}

/** The PEM of a private key file, or null when there is none or it is not a key. @param {string} file */
function readKey(file) {
  try {
    const pem = fs.readFileSync(file, 'utf8');
    crypto.createPrivateKey(pem);
    return pem;
  } catch {
    return null;
  }
}

/** @param {string | null} [reuseKeyPem] an existing server key to certify again (new names), else a new one */
function createServerCert(ca, names, now, reuseKeyPem = null) {
  let keyPem, publicKey;
  if (reuseKeyPem) {
    const key = forge.pki.privateKeyFromPem(reuseKeyPem);
    keyPem = reuseKeyPem;
    publicKey = forge.pki.setRsaPublicKey(key.n, key.e);
  } else {
    ({ keyPem, publicKey } = newKeyPair());
  }
  const cert = forge.pki.createCertificate();
  cert.publicKey = publicKey;
  cert.serialNumber = serialNumber();
  cert.validity.notBefore = new Date(now.getTime() - 3600 * 1000);
  cert.validity.notAfter = new Date(now.getTime() + SERVER_DAYS * DAY_MS);
  const cn = names.find((n) => !net.isIP(n) && n !== 'localhost') || 'localhost';
  cert.setSubject([{ name: 'commonName', value: cn }, { name: 'organizationName', value: 'Robot cell' }]);
  cert.setIssuer(ca.cert.subject.attributes);
  cert.setExtensions([
    { name: 'basicConstraints', cA: false, critical: true },
    { name: 'keyUsage', digitalSignature: true, keyEncipherment: true, critical: true },
    { name: 'extKeyUsage', serverAuth: true },
    { name: 'subjectAltName', altNames: names.map((n) => (net.isIP(n) ? { type: 7, ip: n } : { type: 2, value: n })) },
    { name: 'subjectKeyIdentifier' },
    { name: 'authorityKeyIdentifier', keyIdentifier: ca.cert.generateSubjectKeyIdentifier().getBytes() },
  ]);
  cert.sign(ca.key, forge.md.sha256.create());
  return { keyPem, certPem: forge.pki.certificateToPem(cert) };
}

const safeLabel = (s) => String(s).replace(/[^A-Za-z0-9_.-]/g, '').slice(0, 40) || 'host';
