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

/**
 * A number the node wrote, in the user's locale with the decimals the node gave ("-120.0" -> "-120,0" in Spanish).
 * @param {string} v
 */
function localNumber(v) {
  const decimals = (v.split('.')[1] ?? '').length;
  return fmtNumber(Number(v), { minimumFractionDigits: decimals, maximumFractionDigits: decimals });
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
      p[k] = rename?.(k, v) ?? (NUMBER.test(v) ? localNumber(v) : v);
    }
  }
  return say(p);
}

/**
 * A service response (or a message) whose `message` has a code: the same object with the message in the user's
 * language (cell_msgs MoveNamed, ToolAction, PreviewMove, ...: `code`, `params` beside `message`). Anything else as is.
 * @template T
 * @param {T} r
 * @param {string} [codeKey] @param {string} [paramsKey]
 * @param {Rename} [rename]  how the page names a parameter (a cell-file name by its title in the user's language)
 * @returns {T}
 */
export function localized(r, codeKey = 'code', paramsKey = 'params', rename = undefined) {
  const v = /** @type {any} */ (r);
  if (!v || typeof v !== 'object' || typeof v[codeKey] !== 'string' || !v[codeKey] || typeof v.message !== 'string') return r;
  return { ...v, message: saidText(v[codeKey], paramsOf(v[paramsKey]), v.message, rename) };
}
