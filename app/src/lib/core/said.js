/**
 * What a ROS node said, in the user's language: a text with a stable code and parameters (cell_nodes/said.py:
 * cell_msgs LogEntry `code`, `params` as diagnostic_msgs/KeyValue). The catalogue key of a code is its feature,
 * `_said_`, then the rest with `_` for `.` ("process.stop" -> process_said_stop); "alarm.<code>" is an alarm's code
 * (alarms_code_<code>). A parameter that is itself said nests: `key.code` and `key.<its parameter>`.
 * Without a code, or one the catalogue lacks (a newer robot PC), the node's English shows.
 */
import { m } from '$lib/paraglide/messages.js';
import { fmtNumber } from './i18n.js';

const catalogue = /** @type {Record<string, ((p: Record<string, string | number>) => string) | undefined>} */ (/** @type {unknown} */ (m));
const NUMBER = /^-?\d+(\.\d+)?$/;

/**
 * diagnostic_msgs/KeyValue[] as an object; anything else: none.
 * @param {unknown} list @returns {Record<string, string>}
 */
export function paramsOf(list) {
  /** @type {Record<string, string>} */
  const out = {};
  if (Array.isArray(list)) for (const kv of list) if (kv && typeof kv.key === 'string') out[kv.key] = String(kv.value ?? '');
  return out;
}

/** @param {string} code @returns {string} the catalogue key */
export function saidKey(code) {
  if (code.startsWith('alarm.')) return `alarms_code_${code.slice(6).replaceAll('.', '_')}`;
  const dot = code.indexOf('.');
  return dot < 0 ? code : `${code.slice(0, dot)}_said_${code.slice(dot + 1).replaceAll('.', '_')}`;
}

/**
 * @callback Rename  a parameter's value as the page names it (e.g. an operation's title from the cell file), or
 *   undefined to keep it
 * @param {string} key @param {string} value
 * @returns {string | undefined}
 */

/**
 * @param {string} code
 * @param {Record<string, string>} params
 * @param {string} text  the node's English
 * @param {Rename} [rename]
 * @returns {string}
 */
export function saidText(code, params, text, rename) {
  const say = code ? catalogue[saidKey(code)] : undefined;
  if (typeof say !== 'function') return text;
  /** @type {Record<string, string | number>} */
  const p = {};
  for (const [k, v] of Object.entries(params)) {
    if (k.includes('.')) continue;
    const inner = params[`${k}.code`];
    if (inner !== undefined) {
      /** @type {Record<string, string>} */
      const sub = {};
      for (const [kk, vv] of Object.entries(params)) if (kk.startsWith(`${k}.`) && kk !== `${k}.code`) sub[kk.slice(k.length + 1)] = vv;
      p[k] = saidText(inner, sub, v, rename);
    } else if (k === 'count') {
      p[k] = Number(v);   // for the plural's choice
    } else {
      p[k] = rename?.(k, v) ?? (NUMBER.test(v) ? fmtNumber(Number(v)) : v);
    }
  }
  return say(p);
}
