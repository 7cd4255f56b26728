// Access rules for rosbridge ops: a pure function of (grants, op, target). Everything not granted is denied.
//
// Patterns: "*" matches any run of characters (including "/"), "?" one character; anything else is literal.
// "/cell/*" therefore grants every name under /cell/.

/** @typedef {import('../config/cell-types.js').RosGrants} RosGrants */
/** @typedef {{allow: boolean, reason: string, grant?: string, target?: string}} Decision */

/** Ops that need a grant, the grant kind and the field naming their target. */
export const GRANTED_OPS = /** @type {const} */ ({
  subscribe: ['subscribe', 'topic'],
  publish: ['publish', 'topic'],
  advertise: ['advertise', 'topic'],
  call_service: ['call_service', 'service'],
  advertise_service: ['advertise_service', 'service'],
  // Answering a call is part of serving the service, so it needs the same grant.
  service_response: ['advertise_service', 'service'],
});

/** Ops that only undo or tune the client's own state on its own connection. */
export const FREE_OPS = new Set(['unsubscribe', 'unadvertise', 'unadvertise_service', 'set_level']);

const cache = new Map();
/** @param {string} pattern */
export function globToRegExp(pattern) {
  let re = cache.get(pattern);
  if (!re) {
    const body = pattern.split('').map((c) => (c === '*' ? '.*' : c === '?' ? '.' : c.replace(/[.+^${}()|[\]\\]/g, '\\$&'))).join('');
    re = new RegExp(`^${body}$`);
    cache.set(pattern, re);
  }
  return re;
}

/** @param {string[]|undefined} patterns @param {string} name */
export function matchesAny(patterns, name) {
  return (patterns || []).some((p) => globToRegExp(p).test(name));
}

/**
 * @param {RosGrants|undefined} grants the role's grants from the cell file
 * @param {string} op rosbridge op
 * @param {string|undefined} target topic or service name
 * @returns {Decision}
 */
export function decide(grants, op, target) {
  if (FREE_OPS.has(op)) return { allow: true, reason: `${op} is always allowed` };
  if (op === 'fragment') return { allow: false, reason: 'fragmented ops are not accepted from browsers' };
  const g = GRANTED_OPS[/** @type {keyof typeof GRANTED_OPS} */ (op)];
  if (!g) return { allow: false, reason: `op "${op}" is not allowed` };
  const [kind] = g;
  if (typeof target !== 'string' || !target.startsWith('/')) return { allow: false, reason: `${op} needs an absolute ${g[1]} name` };
  if (matchesAny(grants?.[kind], target)) return { allow: true, reason: 'granted', grant: kind, target };
  return { allow: false, reason: `not allowed to ${kind.replace('_', ' ')} ${target}`, grant: kind, target };
}

/**
 * Check one decoded rosbridge message from a browser.
 * @param {RosGrants|undefined} grants @param {any} msg
 * @returns {Decision & {op: string, id?: string}}
 */
export function checkMessage(grants, msg) {
  if (!msg || typeof msg !== 'object' || Array.isArray(msg) || typeof msg.op !== 'string') {
    return { allow: false, reason: 'not a rosbridge message (an object with an "op" string)', op: String(msg?.op ?? '') };
  }
  const field = GRANTED_OPS[/** @type {keyof typeof GRANTED_OPS} */ (msg.op)]?.[1];
  const target = field ? msg[field] : undefined;
  return { ...decide(grants, msg.op, target), op: msg.op, id: typeof msg.id === 'string' ? msg.id : undefined };
}

/** rosapi services whose answers list names, and how to filter them. */
const ROSAPI_LISTS = {
  '/rosapi/topics': { kind: 'topic', key: 'topics', parallel: ['types'] },
  '/rosapi/topics_for_type': { kind: 'topic', key: 'topics', parallel: [] },
  '/rosapi/topics_and_raw_types': { kind: 'topic', key: 'topics', parallel: ['types', 'typedefs_full_text'] },
  '/rosapi/services': { kind: 'service', key: 'services', parallel: [] },
  '/rosapi/services_for_type': { kind: 'service', key: 'services', parallel: [] },
};

/** @param {string} service */
export const isFilteredRosapi = (service) => Object.hasOwn(ROSAPI_LISTS, service);

/**
 * A role sees only the topics it may subscribe or publish to and the services it may call.
 * @param {RosGrants|undefined} grants @param {string} service @param {any} values
 */
export function filterRosapiValues(grants, service, values) {
  const spec = ROSAPI_LISTS[/** @type {keyof typeof ROSAPI_LISTS} */ (service)];
  if (!spec || !values || !Array.isArray(values[spec.key])) return values;
  const visible = spec.kind === 'topic'
    ? (n) => matchesAny(grants?.subscribe, n) || matchesAny(grants?.publish, n)
    : (n) => matchesAny(grants?.call_service, n);
  const keep = values[spec.key].map((n) => typeof n === 'string' && visible(n));
  const out = { ...values, [spec.key]: values[spec.key].filter((_, i) => keep[i]) };
  for (const p of spec.parallel) if (Array.isArray(values[p]) && values[p].length === keep.length) out[p] = values[p].filter((_, i) => keep[i]);
  return out;
}
