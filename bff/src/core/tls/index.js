// HTTPS for phones on the shop floor: certificates, /ca.crt + /trust, and the HTTP -> HTTPS redirect.
export { ensureCertificates, certificateNames, CA_DAYS, SERVER_DAYS, RENEW_BEFORE_DAYS } from './certificates.js';
export { tlsRoutes, httpsRedirect, httpsUrlFor, hostOf, isLoopback, HTTP_ALLOWED_PATHS } from './routes.js';
