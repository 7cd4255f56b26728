// The HTTP API as an OpenAPI 3.1 document, and request validation from it (ajv).
import Ajv2020 from 'ajv/dist/2020.js';

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
const unauthorized = { description: 'Not logged in', ...json(error) };
const forbidden = { description: 'Role may not', ...json(error) };

export const openapi = {
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
    '/api/system': {
      get: { summary: 'System overview (admin): health, cell file, users', security: [{ session: [] }], responses: { 200: { description: 'Overview', ...json({ type: 'object' }) }, 401: unauthorized, 403: forbidden } },
    },
    '/api/openapi.json': {
      get: { summary: 'This document', security: [], responses: { 200: { description: 'OpenAPI 3.1 document', ...json({ type: 'object' }) } } },
    },
  },
};

/** Express path for an OpenAPI path ("/api/x/{id}" -> "/api/x/:id"). @param {string} p */
export const expressPath = (p) => p.replace(/\{(\w+)\}/g, ':$1');

/** Middleware validating JSON request bodies against the document. */
export function validateRequests() {
  const ajv = new Ajv2020({ allErrors: true, strict: false });
  /** @type {Map<string, import('ajv').ValidateFunction>} */
  const validators = new Map();
  for (const [p, ops] of Object.entries(openapi.paths)) {
    for (const [method, op] of Object.entries(ops)) {
      const schema = /** @type {any} */ (op).requestBody?.content?.['application/json']?.schema;
      if (schema) validators.set(`${method.toUpperCase()} ${p}`, ajv.compile(schema));
    }
  }
  /** @type {import('express').RequestHandler} */
  return (req, res, next) => {
    const v = validators.get(`${req.method} ${req.path}`);
    if (!v) return next();
    if (!req.is('application/json')) return res.status(415).json({ error: 'expected application/json' });
    if (!v(req.body)) {
      const e = v.errors[0];
      return res.status(400).json({ error: `invalid request body${e.instancePath ? ' at ' + e.instancePath : ''}: ${e.message}` });
    }
    next();
  };
}
