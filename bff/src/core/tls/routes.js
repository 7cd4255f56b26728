// GET /ca.crt and GET /trust (how to trust the local CA on a phone), and the HTTP -> HTTPS redirect.
// Both routes work over plain HTTP and without a session: they are how a phone gets to HTTPS in the first place.
import crypto from 'node:crypto';
import net from 'node:net';
import { Router } from 'express';
import QRCode from 'qrcode';

/** Paths that stay on plain HTTP for every client. */
export const HTTP_ALLOWED_PATHS = ['/ca.crt', '/trust', '/api/health'];

/**
 * @param {{caCertPem: string|null, httpsUrl: string | ((req: import('express').Request) => string|null),
 *   fingerprint?: string}} o httpsUrl: the URL phones should use, or a function of the request
 *   (e.g. (req) => httpsUrlFor(req, env.tlsPort)); fingerprint: shown when there is no CA (user certificate).
 */
export function tlsRoutes({ caCertPem, httpsUrl, fingerprint }) {
  const r = Router();
  const caFingerprint = caCertPem ? new crypto.X509Certificate(caCertPem).fingerprint256 : null;

  r.use((req, res, next) => {
    res.setHeader('X-Content-Type-Options', 'nosniff');
    next();
  });
  r.get('/ca.crt', (req, res) => {
    if (!caCertPem) return res.status(404).type('text/plain').send('No local CA: this server uses a user-provided certificate.\n');
    res.setHeader('Cache-Control', 'no-cache');
    res.type('application/x-x509-ca-cert').send(caCertPem);
  });

  r.get('/trust', async (req, res, next) => {
    try {
      const url = (typeof httpsUrl === 'function' ? httpsUrl(req) : httpsUrl) || null;
      const qr = url ? await QRCode.toString(url, { type: 'svg', margin: 2, errorCorrectionLevel: 'M' }) : '';
      const html = trustPage({ url, qr, hasCa: Boolean(caCertPem), fingerprint: caFingerprint || fingerprint || null });
      res.setHeader('Content-Security-Policy', `default-src 'none'; style-src '${STYLE_HASH}'; img-src data:; frame-ancestors 'none'; base-uri 'none'; form-action 'none'`);
      res.setHeader('Cache-Control', 'no-store');
      res.type('html').send(html);
    } catch (e) {
      next(e);
    }
  });
  return r;
}

/**
 * The HTTPS URL for the host name the client used to reach us (so a phone that typed an IP address gets that IP),
 * or null when the Host header is not a plain host name / address.
 * @param {import('node:http').IncomingMessage} req @param {number} tlsPort
 */
export function httpsUrlFor(req, tlsPort) {
  const host = hostOf(req);
  if (!host) return null;
  return `https://${host}${tlsPort === 443 ? '' : `:${tlsPort}`}/`;
}

/** Host name from the Host header without the port; IPv6 literals keep their brackets. null when malformed. */
export function hostOf(req) {
  const m = /^(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+)(?::\d{1,5})?$/.exec(String(req.headers.host || ''));
  if (!m) return null;
  if (m[1].startsWith('[') && net.isIPv6(m[1].slice(1, -1)) === false) return null;
  return m[1];
}

/** 127.0.0.0/8, ::1 and IPv4-mapped loopback. @param {string|undefined} addr */
export function isLoopback(addr) {
  if (!addr) return false;
  const a = addr.toLowerCase().replace(/%.*$/, '');
  if (a === '::1') return true;
  const v4 = a.startsWith('::ffff:') ? a.slice(7) : a;
  return net.isIPv4(v4) && v4.startsWith('127.');
}

/**
 * Middleware for the plain-HTTP server: clients other than loopback are sent (308) to
 * https://<same host name>:<tlsPort><path>, except for HTTP_ALLOWED_PATHS. Requests that arrived over TLS pass,
 * so one Express app can serve both the HTTP and the HTTPS server.
 * @param {{tlsPort: number}} o
 * @returns {import('express').RequestHandler}
 */
export function httpsRedirect({ tlsPort }) {
  return (req, res, next) => {
    if (/** @type {import('node:tls').TLSSocket} */ (req.socket)?.encrypted || HTTP_ALLOWED_PATHS.includes(req.path)) return next();
    if (isLoopback(req.socket?.remoteAddress)) return next();
    const host = hostOf(req);
    if (!host) return res.status(400).type('text/plain').send('Bad Host header\n');
    const port = tlsPort === 443 ? '' : `:${tlsPort}`;
    // req.originalUrl is path + query as sent; it must be a path (not "//evil" or an absolute URL).
    const target = req.originalUrl.startsWith('/') && !req.originalUrl.startsWith('//') ? req.originalUrl : '/';
    res.redirect(308, `https://${host}${port}${target}`);
  };
}

const STYLE = `
:root{color-scheme:light dark;--fg:#1b1f24;--bg:#f6f7f9;--card:#fff;--muted:#57606a;--accent:#0b63c5}
@media (prefers-color-scheme:dark){:root{--fg:#e6e8eb;--bg:#101418;--card:#1b2128;--muted:#9aa4ae;--accent:#5aa7ff}}
*{box-sizing:border-box}
body{margin:0;font:16px/1.5 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;color:var(--fg);background:var(--bg)}
main{max-width:40rem;margin:0 auto;padding:1rem}
h1{font-size:1.4rem;margin:.5rem 0 1rem}
h2{font-size:1.1rem;margin:0 0 .5rem}
section{background:var(--card);border-radius:12px;padding:1rem;margin:0 0 1rem;box-shadow:0 1px 3px rgba(0,0,0,.12)}
ol{padding-left:1.4rem;margin:.25rem 0}
li{margin:.35rem 0}
a.button{display:block;text-align:center;padding:.9rem;border-radius:10px;background:var(--accent);color:#fff;font-weight:600;text-decoration:none;font-size:1.05rem}
.url{font:600 1.05rem ui-monospace,Menlo,Consolas,monospace;word-break:break-all}
.qr{display:block;width:min(70vw,260px);margin:.75rem auto;background:#fff;padding:6px;border-radius:8px}
.qr svg{display:block;width:100%;height:auto}
.fp{font:.85rem ui-monospace,Menlo,Consolas,monospace;word-break:break-all;color:var(--muted)}
.muted{color:var(--muted);font-size:.92rem}
b{font-weight:600}
`;
const STYLE_HASH = `sha256-${crypto.createHash('sha256').update(STYLE).digest('base64')}`;

const esc = (s) => String(s).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]);

/** @param {{url: string|null, qr: string, hasCa: boolean, fingerprint: string|null}} o */
function trustPage({ url, qr, hasCa, fingerprint }) {
  const urlBlock = url
    ? `<p>Open this address on the phone, or scan the code with the camera:</p>
<p class="url"><a href="${esc(url)}">${esc(url)}</a></p>
<div class="qr" role="img" aria-label="QR code of ${esc(url)}">${qr}</div>`
    : '<p>Open this page with the address of the robot PC (as you typed it on the phone) to see the secure address.</p>';
  const caSteps = hasCa
    ? `<section>
<h2>1. Download the certificate</h2>
<p>The robot PC signs its own secure connection. Your phone trusts it once you install this certificate.</p>
<p><a class="button" href="/ca.crt" download="robot-cell-ca.crt">Download certificate</a></p>
</section>
<section>
<h2>2a. Android</h2>
<ol>
<li>Tap <b>Download certificate</b> above. If asked, keep the file.</li>
<li>Open <b>Settings &gt; Security &gt; Encryption &amp; credentials &gt; Install a certificate &gt; CA certificate</b>. (On some phones: Settings &gt; Security &amp; privacy &gt; More security settings.)</li>
<li>Tap <b>Install anyway</b>, confirm with your screen lock, and pick the downloaded file <b>ca.crt</b> or <b>robot-cell-ca.crt</b>.</li>
<li>Open the secure address below.</li>
</ol>
</section>
<section>
<h2>2b. iPhone and iPad</h2>
<ol>
<li>Open this page in <b>Safari</b> and tap <b>Download certificate</b>. Allow the download of the configuration profile.</li>
<li>Open <b>Settings &gt; General &gt; VPN &amp; Device Management</b>, tap the downloaded profile and tap <b>Install</b>.</li>
<li>Open <b>Settings &gt; General &gt; About &gt; Certificate Trust Settings</b> and switch on <b>full trust</b> for the robot cell certificate.</li>
<li>Open the secure address below.</li>
</ol>
</section>`
    : `<section><p>This server uses a certificate provided by your IT department. If your phone shows a warning, ask them to install their certificate authority on the phone.</p></section>`;
  const fp = fingerprint
    ? `<section><h2>Check</h2><p class="muted">Before trusting it, you can compare the certificate's SHA-256 fingerprint with the one your phone shows:</p><p class="fp">${esc(fingerprint)}</p></section>`
    : '';
  return `<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="referrer" content="no-referrer">
<title>Secure connection to the robot cell</title>
<style>${STYLE}</style>
</head>
<body>
<main>
<h1>Secure connection to the robot cell</h1>
<p class="muted">The app works offline and can be added to the home screen only over a secure (https) connection. Do these steps once per phone.</p>
${caSteps}
<section>
<h2>3. Secure address</h2>
${urlBlock}
</section>
${fp}
</main>
</body>
</html>
`;
}
