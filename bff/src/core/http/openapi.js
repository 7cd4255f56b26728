// The HTTP API as an OpenAPI 3.1 document (the core's paths plus each feature's), and request validation from it (ajv).
import Ajv2020Module from 'ajv/dist/2020.js';
import { LOCALES } from '../auth/users.js';
import { errorBody } from './errors.js';

// ajv is CommonJS: under Node its default import is the class itself.
const Ajv2020 = /** @type {typeof Ajv2020Module.default} */ (/** @type {unknown} */ (Ajv2020Module));

const json = (schema) => ({ content: { 'application/json': { schema } } });
// code and params: a stable error code and its values, for the app to say in the user's language.
const error = { type: 'object', required: ['error'], properties: { error: { type: 'string' }, code: { type: 'string' }, params: { type: 'object' } } };
// locale: the language the user chose (absent: the browser's).
const user = { type: 'object', required: ['username', 'role'], properties: { username: { type: 'string' }, role: { type: 'string' }, locale: { type: 'string' } } };
const health = {
  type: 'object', required: ['status', 'ros'],
  properties: {
    status: { const: 'ok' }, version: { type: 'string' }, uptime_s: { type: 'number' },
    ros: { type: 'object', properties: { master: { type: 'boolean' }, rosbridge: { type: 'boolean' } } },
  },
};
const lease = { type: 'object', required: ['holder', 'you'], properties: { holder: { type: ['object', 'null'] }, you: { type: 'boolean' } } };
// holder.resumed_at: the BFF restarted and gave the lease back to its holder. ended: why this session lost control.
const leaseRefused = { type: 'object', required: ['error'], properties: { error: { type: 'string' }, code: { type: 'string' }, params: { type: 'object' }, holder: { type: ['object', 'null'] }, ended: { type: 'string' } } };
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
        responses: {
          200: { description: 'Logged in', ...json(user) },
          401: { description: 'Wrong user name or password', ...json(error) },
          429: {
            description: 'Too many failed attempts for this user name or address; try again after Retry-After seconds',
            headers: { 'Retry-After': { description: 'Seconds to wait', schema: { type: 'string', pattern: '^[0-9]+$' } } }, ...json(error),
          },
        },
      },
    },
    '/api/auth/logout': {
      // Works with or without a session (clears the cookie either way): the session is optional here.
      post: { summary: 'Log out; revokes the session token', security: [{ session: [] }, {}], responses: { 204: { description: 'Logged out' } } },
    },
    '/api/auth/me': {
      get: { summary: 'Who is logged in', security: [{ session: [] }], responses: { 200: { description: 'The user', ...json(user) }, 401: unauthorized } },
    },
    '/api/auth/me/preferences': {
      put: {
        summary: "Keep the user's language with the account (null: follow the browser)", security: [{ session: [] }],
        requestBody: { required: true, ...json({
          type: 'object', additionalProperties: false, required: ['locale'],
          properties: { locale: { oneOf: [{ enum: LOCALES }, { type: 'null' }] } },
        }) },
        responses: { 200: { description: 'The user', ...json(user) }, 400: { description: 'Not a language of the app', ...json(error) }, 401: unauthorized, 409: { description: 'The account was removed', ...json(error) } },
      },
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
      post: { summary: 'Keep control (send about every 500 ms; lost after the cell file\'s heartbeat timeout)', security: [{ session: [] }], responses: { 200: { description: 'Still yours', ...json(lease) }, 401: unauthorized, 409: { description: 'Not yours (ended: why you lost it, when you were the last holder)', ...json(leaseRefused) } } },
    },
    '/api/control/release': {
      post: { summary: 'Give control back', security: [{ session: [] }], responses: { 204: { description: 'Released' }, 401: unauthorized } },
    },
    '/api/openapi.json': {
      get: { summary: 'This document', security: [], responses: { 200: { description: 'OpenAPI 3.1 document', ...json({ type: 'object' }) } } },
    },
  },
};

/** Methods that change state: refused cross-origin (403), and their bodies are parsed (400/413/415). */
export const STATE_CHANGING = (method) => !['get', 'head', 'options'].includes(method.toLowerCase());

/** Does the operation require a session (no anonymous alternative in its security list)? */
const requiresSession = (op) => Array.isArray(op.security) && op.security.length > 0 && op.security.every((s) => Object.keys(s).length > 0);

/**
 * The statuses every operation can answer because of what the core does around it, added from facts about the
 * operation (its method, security, parameters, whether a feature's page guard stands before it). A status the
 * operation already declares keeps its description, extended with the generic reason.
 * @param {string} method @param {any} op @param {{feature: boolean}} o feature: served behind the page guard
 */
function completeOperation(method, op, { feature }) {
  const responses = { ...op.responses };
  const add = (status, description, extra = {}) => {
    const had = responses[status];
    if (!had) responses[status] = { description, ...extra, ...json(error) };
    else if (!had.description.toLowerCase().includes(description.toLowerCase())) responses[status] = { ...had, description: `${had.description}; or: ${description}` };
  };
  const secured = requiresSession(op);
  const params = (op.parameters || []).filter((p) => p.in === 'path' || p.in === 'query');
  if (secured) add(401, 'Not logged in');
  if (feature && secured) add(403, "The caller's role may not use this page");
  if (STATE_CHANGING(method)) {
    add(403, 'Cross-origin request refused (Origin names another host)');
    add(400, 'Malformed or invalid request body');
    add(413, 'Request body too large');
    add(415, 'Unsupported content type, charset or content encoding');
  }
  if (params.length) add(400, params.some((p) => p.in === 'path') ? 'Invalid parameter (or malformed percent-encoding in the path)' : 'Invalid parameter');
  add(405, 'Method not allowed on this path', { headers: { Allow: { description: 'The methods this path supports', schema: { type: 'string' } } } });
  // Node's HTTP parser refuses a request line plus headers over its limit (16 kB) before the app sees it, empty body.
  responses[431] ??= { description: 'Request line and headers too large (over 16 kB, e.g. a very long query or path)' };
  return { ...op, responses };
}

/**
 * @param {import('../features/feature.js').Feature[]} features
 * @returns {typeof core}
 */
export function buildOpenApi(features) {
  /** @type {Record<string, any>} */
  const paths = {};
  const put = (p, ops, feature) => {
    paths[p] = Object.fromEntries(Object.entries(ops).map(([m, op]) => [m, completeOperation(m, op, { feature })]));
  };
  for (const [p, ops] of Object.entries(core.paths)) put(p, ops, false);
  for (const f of features) {
    for (const [p, ops] of Object.entries(f.openapi || {})) {
      if (paths[p]) throw new Error(`feature "${f.id}" declares ${p}, which is already in the document`);
      put(p, ops, true);
    }
  }
  // This document's own path last, as before.
  const { '/api/openapi.json': self, ...rest } = paths;
  return /** @type {typeof core} */ ({ ...core, paths: { ...rest, '/api/openapi.json': self } });
}

/** Express path for an OpenAPI path ("/api/x/{id}" -> "/api/x/:id"). @param {string} p */
export const expressPath = (p) => p.replace(/\{(\w+)\}/g, ':$1');

const escapeRe = (s) => s.replace(/[.*+?^${}()|[\]\\]/g, '\\$&');

/**
 * A request path matcher for an OpenAPI path that matches as Express 5 routes do by default: case-insensitive, an
 * optional trailing slash, a template segment is one non-empty segment (still percent-encoded).
 * @param {string} p
 */
export const pathRegExp = (p) => new RegExp(`^${p.split(/(\{\w+\})/).map((s) => (/^\{\w+\}$/.test(s) ? '[^/]+' : escapeRe(s))).join('')}/?$`, 'i');

/**
 * The document's operations, found by request method and path.
 * @param {typeof core} openapi
 */
export function operations(openapi) {
  const paths = Object.entries(openapi.paths).map(([p, ops]) => ({ path: p, ops: /** @type {Record<string, any>} */ (ops), re: pathRegExp(p) }));
  return {
    /** The documented paths a request path falls on. @param {string} reqPath */
    paths: (reqPath) => paths.filter((x) => x.re.test(reqPath)),
    /** The operation for a request, or null. @param {string} method @param {string} reqPath */
    find(method, reqPath) {
      const m = method.toLowerCase();
      for (const x of paths) if (x.ops[m] && x.re.test(reqPath)) return { path: x.path, op: x.ops[m] };
      return null;
    },
  };
}

/**
 * Middleware validating JSON request bodies against the document (templated paths included). Validation comes after
 * the access checks, so a caller who may not use a route learns nothing about its rules (and the route's own refusal,
 * audited, is what it gets): an operation that needs a session is left to its route when there is none, and the
 * features mount their own validator after their page guard (`include` picks the document paths one validator owns).
 * A refused body (400, 415) is audited like any other refusal (op `request.invalid`, the route as target).
 * @param {typeof core} openapi
 * @param {{include?: (path: string) => boolean, audit?: {record: (e: object) => void}}} [o]
 */
export function validateRequests(openapi, { include = () => true, audit } = {}) {
  const ajv = new Ajv2020({ allErrors: true, strict: false, verbose: true });
  const ops = operations(openapi);
  /** @type {Map<object, import('ajv').ValidateFunction>} */
  const validators = new Map();
  for (const path of Object.values(openapi.paths)) {
    for (const op of Object.values(path)) {
      const schema = /** @type {any} */ (op).requestBody?.content?.['application/json']?.schema;
      if (schema) validators.set(op, ajv.compile(schema));
    }
  }
  /** @type {import('express').RequestHandler} */
  return (req, res, next) => {
    const found = ops.find(req.method, req.path);
    const validate = found && include(found.path) && validators.get(found.op);
    if (!validate) return next();
    if (needsSession(found.op) && !req.session) return next();
    const body = found.op.requestBody;
    if (!body.required && !Number(req.headers['content-length'] || 0) && !req.headers['transfer-encoding']) return next();
    /** @param {number} status @param {string} error */
    const refuse = (status, error) => {
      const s = /** @type {any} */ (req).session;
      audit?.record({ user: s?.username ?? null, role: s?.role ?? null, ip: req.ip || null, op: 'request.invalid',
        target: `${req.method} ${found.path}`, outcome: 'denied', detail: `${status}: ${error}` });
      return res.status(status).json(errorBody(error, status === 415 ? 'request.not_json' : 'request.invalid', { detail: error }));
    };
    if (!req.is('application/json')) return refuse(415, 'expected application/json');
    if (!validate(req.body)) {
      const e = validate.errors[0];
      // A pattern is long and says little to a user: name the rule's description or the field instead.
      const why = e.keyword === 'pattern' ? `does not have the required form${e.parentSchema?.description ? ` (${e.parentSchema.description})` : ''}` : e.message;
      return refuse(400, `invalid request body${e.instancePath ? ' at ' + e.instancePath : ''}: ${why}`);
    }
    next();
  };
}

/** An operation whose every security alternative names the session (logout's `{}` alternative makes it optional). @param {any} op */
const needsSession = (op) => Array.isArray(op.security) && op.security.length > 0 && op.security.every((alt) => 'session' in alt);

/**
 * For a documented path asked with a method the document does not declare there: 405 with an Allow header (OPTIONS
 * answers 204 with it). Mounted before the routes, so the document decides; requests with a declared method and
 * requests on undocumented paths go on (to their route, or to the 404).
 * @param {typeof core} openapi
 * @returns {import('express').RequestHandler}
 */
export function methodNotAllowed(openapi) {
  const ops = operations(openapi);
  return (req, res, next) => {
    const hits = ops.paths(req.path);
    if (!hits.length) return next();
    const methods = new Set(hits.flatMap((h) => Object.keys(h.ops).map((m) => m.toUpperCase())));
    // HEAD is answered by GET routes.
    if (methods.has(req.method) || (req.method === 'HEAD' && methods.has('GET'))) return next();
    if (methods.has('GET')) methods.add('HEAD');
    methods.add('OPTIONS');
    const allow = [...methods].join(', ');
    res.setHeader('Allow', allow);
    res.setHeader('Cache-Control', 'no-store');
    if (req.method === 'OPTIONS') return res.status(204).end();
    res.status(405).json({ error: `method ${req.method} is not allowed on ${req.path.slice(0, 200)} (allowed: ${allow})` });
  };
}
