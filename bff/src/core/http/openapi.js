// The HTTP API as an OpenAPI 3.1 document (the core's paths plus each feature's), and request validation from it (ajv).
import Ajv2020Module from 'ajv/dist/2020.js';

// ajv is CommonJS: under Node its default import is the class itself.
const Ajv2020 = /** @type {typeof Ajv2020Module.default} */ (/** @type {unknown} */ (Ajv2020Module));

const json = (schema) => ({ content: { 'application/json': { schema } } });
const error = { type: 'object', required: ['error'], properties: { error: { type: 'string' } } };
const user = { type: 'object', required: ['username', 'role'], properties: { username: { type: 'string' }, role: { type: 'string' } } };
const health = {
  type: 'object', required: ['status', 'ros'],
  properties: {
    status: { const: 'ok' }, version: { type: 'string' }, uptime_s: { type: 'number' },
    ros: { type: 'object', properties: { master: { type: 'boolean' }, rosbridge: { type: 'boolean' } } },
  },
};
const lease = { type: 'object', required: ['holder', 'you'], properties: { holder: { type: ['object', 'null'] }, you: { type: 'boolean' } } };
const unauthorized = { description: 'Not logged in', ...json(error) };

/** The core's part of the document; buildOpenApi adds the features'. */
const core = {
  openapi: '3.1.0',
  info: { title: 'Robot cell BFF', version: '0.1.0', description: 'HTTP API of the backend-for-frontend. The /ros WebSocket speaks the rosbridge v2 protocol.' },
  components: {
    securitySchemes: { session: { type: 'apiKey', in: 'cookie', name: 'cell_session' } },
  },
  paths: {
    '/api/health': {
      get: { summary: 'Liveness and ROS reachability', security: [], responses: { 200: { description: 'Up', ...json(health) } } },
    },
    '/api/auth/login': {
      post: {
        summary: 'Log in; sets the HttpOnly session cookie', security: [],
        requestBody: { required: true, ...json({
          type: 'object', additionalProperties: false, required: ['username', 'password'],
          properties: { username: { type: 'string', minLength: 1, maxLength: 64 }, password: { type: 'string', minLength: 1, maxLength: 256 } },
        }) },
        responses: { 200: { description: 'Logged in', ...json(user) }, 400: { description: 'Bad request', ...json(error) }, 401: { description: 'Wrong user name or password', ...json(error) } },
      },
    },
    '/api/auth/logout': {
      post: { summary: 'Log out; revokes the session token', security: [{ session: [] }], responses: { 204: { description: 'Logged out' } } },
    },
    '/api/auth/me': {
      get: { summary: 'Who is logged in', security: [{ session: [] }], responses: { 200: { description: 'The user', ...json(user) }, 401: unauthorized } },
    },
    '/api/config': {
      get: { summary: "The cell file as the caller's role needs it", security: [{ session: [] }], responses: { 200: { description: 'Filtered cell file', ...json({ type: 'object' }) }, 401: unauthorized } },
    },
    '/api/control': {
      get: { summary: 'Who holds control of motion', security: [{ session: [] }], responses: { 200: { description: 'Lease state', ...json(lease) }, 401: unauthorized } },
    },
    '/api/control/take': {
      post: {
        summary: 'Take control of motion (roles with take_over in the cell file may take it over with force)', security: [{ session: [] }],
        requestBody: { required: false, ...json({ type: 'object', additionalProperties: false, properties: { force: { type: 'boolean' } } }) },
        responses: { 200: { description: 'You hold control', ...json(lease) }, 401: unauthorized, 409: { description: 'Held by someone else', ...json(error) } },
      },
    },
    '/api/control/heartbeat': {
      post: { summary: 'Keep control (send about every 500 ms; lost after the cell file\'s heartbeat timeout)', security: [{ session: [] }], responses: { 200: { description: 'Still yours', ...json(lease) }, 401: unauthorized, 409: { description: 'Not yours', ...json(error) } } },
    },
    '/api/control/release': {
      post: { summary: 'Give control back', security: [{ session: [] }], responses: { 204: { description: 'Released' }, 401: unauthorized } },
    },
    '/api/openapi.json': {
      get: { summary: 'This document', security: [], responses: { 200: { description: 'OpenAPI 3.1 document', ...json({ type: 'object' }) } } },
    },
  },
};

/**
 * @param {import('../features/feature.js').Feature[]} features
 * @returns {typeof core}
 */
export function buildOpenApi(features) {
  const paths = { ...core.paths };
  for (const f of features) {
    for (const [p, ops] of Object.entries(f.openapi || {})) {
      if (paths[p]) throw new Error(`feature "${f.id}" declares ${p}, which is already in the document`);
      paths[p] = ops;
    }
  }
  // This document's own path last, as before.
  const { '/api/openapi.json': self, ...rest } = paths;
  return { ...core, paths: { ...rest, '/api/openapi.json': self } };
}

/** Express path for an OpenAPI path ("/api/x/{id}" -> "/api/x/:id"). @param {string} p */
export const expressPath = (p) => p.replace(/\{(\w+)\}/g, ':$1');

/** Middleware validating JSON request bodies against the document (templated paths included). @param {typeof core} openapi */
export function validateRequests(openapi) {
  const ajv = new Ajv2020({ allErrors: true, strict: false });
  /** @type {{method: string, re: RegExp, validate: import('ajv').ValidateFunction, required: boolean}[]} */
  const routes = [];
  for (const [p, ops] of Object.entries(openapi.paths)) {
    for (const [method, op] of Object.entries(ops)) {
      const body = /** @type {any} */ (op).requestBody;
      const schema = body?.content?.['application/json']?.schema;
      if (!schema) continue;
      const re = new RegExp(`^${p.replace(/[.]/g, '\\.').replace(/\{\w+\}/g, '[^/]+')}$`);
      routes.push({ method: method.toUpperCase(), re, validate: ajv.compile(schema), required: !!body.required });
    }
  }
  /** @type {import('express').RequestHandler} */
  return (req, res, next) => {
    const r = routes.find((x) => x.method === req.method && x.re.test(req.path));
    if (!r) return next();
    if (!r.required && !Number(req.headers['content-length'] || 0) && !req.headers['transfer-encoding']) return next();
    if (!req.is('application/json')) return res.status(415).json({ error: 'expected application/json' });
    if (!r.validate(req.body)) {
      const e = r.validate.errors[0];
      return res.status(400).json({ error: `invalid request body${e.instancePath ? ' at ' + e.instancePath : ''}: ${e.message}` });
    }
    next();
  };
}
