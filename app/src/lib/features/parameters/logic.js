/**
 * The Parameters page's plain logic: the node's definitions and values, typed validation in place (the node
 * validates again and has the last word), the diff shown before Save, and the local draft kept while offline.
 * No Svelte, no ROS: tests import it directly.
 */

import { m } from '$lib/paraglide/messages.js';
import { cellText, getLocale } from '../../core/i18n.js';
import { localized, paramsOf, saidText } from '../../core/said.js';

export const FEATURE_ID = 'parameters';

export const NAMES = Object.freeze({
  get: { service: '/cell/parameters/get', type: 'cell_msgs/GetParameters' },
  set: { service: '/cell/parameters/set', type: 'cell_msgs/SetParameters' },
  values: { topic: '/cell/parameters/values', type: 'cell_msgs/ParameterValues' },
});

/**
 * @typedef {object} ParamDef
 * @property {string} id
 * @property {string} category  the node's (English): groups the page's sections
 * @property {string | Record<string, string>} categoryTitle  the section's title (the cell file's, per language)
 * @property {string | Record<string, string>} label  shown through cellText
 * @property {'int' | 'float' | 'bool' | 'string' | 'enum'} type
 * @property {string} unit
 * @property {number | null} min
 * @property {number | null} max
 * @property {string[]} options
 * @property {number | null} decimals  float: at most this many digits after the point
 * @property {number} maxLength  string: at most this many characters
 * @property {string} value  the saved value, as text
 * @property {string} defaultValue
 */

/** @param {any} t @returns {ParamDef['type']} */
const typeOf = (t) => (['int', 'float', 'bool', 'string', 'enum'].includes(t) ? t : 'string');

/**
 * One definition from the node's answer (cell_msgs/Parameter). The node knows a label and a category in English;
 * the cell file's item of the same id may give them per language (shown through cellText).
 * @param {any} p
 * @param {Record<string, { label?: string | Record<string, string>, category?: string | Record<string, string> }>} [texts]
 *   the cell file's parameters.items by id
 * @returns {ParamDef}
 */
export function paramDef(p, texts) {
  const id = String(p?.id ?? '');
  const own = texts && Object.hasOwn(texts, id) ? texts[id] : undefined;
  const category = String(p?.category || m.parameters_category_general());
  return {
    id,
    category,
    categoryTitle: (p?.category && typeof own?.category === 'object' && own.category) || category,
    label: (typeof own?.label === 'object' && own.label) || String(p?.label || p?.id || ''),
    type: typeOf(p?.type),
    unit: String(p?.unit ?? ''),
    min: p?.has_min ? Number(p.min) : null,
    max: p?.has_max ? Number(p.max) : null,
    options: Array.isArray(p?.options) ? p.options.map(String) : [],
    decimals: Number.isInteger(p?.decimals) && p.decimals >= 0 ? p.decimals : null,
    maxLength: Number(p?.max_length) > 0 ? Number(p.max_length) : 200,
    value: String(p?.value ?? ''),
    defaultValue: String(p?.default_value ?? ''),
  };
}

/** Definitions grouped by category, in first-seen order. @param {ParamDef[]} defs */
export function byCategory(defs) {
  /** @type {Map<string, ParamDef[]>} */
  const m = new Map();
  for (const d of defs) {
    if (!m.has(d.category)) m.set(d.category, []);
    m.get(d.category)?.push(d);
  }
  return [...m].map(([category, items]) => ({ category, title: items[0].categoryTitle, items }));
}

// ---- numbers in the user's locale ----
// The node writes numbers with a decimal point ("0.5", "-3", "1e-05") and takes them back so. The page shows them with
// the user's decimal separator and minus sign ("0,5", "−3" in Finnish), digits unchanged (60.0 stays 60.0), and
// takes what the user types in either form.

const PLAIN_NUMBER = /^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$/;

/** The user's decimal separator and minus sign. */
function numberSymbols() {
  const parts = new Intl.NumberFormat(getLocale()).formatToParts(-1.5);
  return {
    decimal: parts.find((x) => x.type === 'decimal')?.value ?? '.',
    minus: parts.find((x) => x.type === 'minusSign')?.value ?? '-',
  };
}

/**
 * A number as the node writes it, in the user's locale; any other text as it is.
 * @param {string} text
 */
export function localNumber(text) {
  const s = String(text ?? '');
  if (!PLAIN_NUMBER.test(s.trim())) return s;
  const { decimal, minus } = numberSymbols();
  return s.replace('.', decimal).replace(/^(\s*)-/, `$1${minus}`);
}

/**
 * A number typed in the user's locale ("−0,5") as the node takes it ("-0.5"); other text trimmed, as it is.
 * @param {string} text
 */
function nodeNumber(text) {
  const { decimal, minus } = numberSymbols();
  let s = String(text ?? '').trim().replace(/^[\u2212]/, '-');
  if (minus !== '-' && s.startsWith(minus)) s = `-${s.slice(minus.length)}`;
  if (decimal !== '.' && s.split(decimal).length === 2 && !s.includes('.')) s = s.replace(decimal, '.');
  return s;
}

/** @param {number} n */
const show = (n) => localNumber(String(n));

/** The saved value as the page shows it (numbers in the user's locale). @param {ParamDef} d */
export function shownValue(d) {
  return d.type === 'int' || d.type === 'float' ? localNumber(d.value) : d.value;
}

/**
 * Why a value is not acceptable for its parameter ('' when it is). Texts name the field, the value and the limit.
 * @param {ParamDef} d @param {string} text
 */
export function validate(d, text) {
  const typed = String(text ?? '').trim();
  const v = canonical(d, text);
  const label = cellText(d.label);
  const unit = d.unit ? ` ${d.unit}` : '';
  const range = (/** @type {number} */ n) => {
    if (d.min !== null && n < d.min) return m.parameters_below_min({ label, value: show(n), unit, min: show(d.min) });
    if (d.max !== null && n > d.max) return m.parameters_above_max({ label, value: show(n), unit, max: show(d.max) });
    return '';
  };
  switch (d.type) {
    case 'int':
      if (!/^[+-]?\d+$/.test(v)) return m.parameters_not_whole({ label, value: typed });
      return range(Number(v));
    case 'float': {
      if (v === '' || !PLAIN_NUMBER.test(v)) return m.parameters_not_number({ label, value: typed });
      const frac = /^[^eE]*\.(\d+)/.exec(v)?.[1] ?? '';
      if (d.decimals !== null && !/[eE]/.test(v) && frac.replace(/0+$/, '').length > d.decimals) {
        return m.parameters_too_many_decimals({ label, count: d.decimals });
      }
      return range(Number(v));
    }
    case 'bool':
      return v === 'true' || v === 'false' ? '' : m.parameters_not_bool({ label, value: v });
    case 'enum':
      return d.options.includes(v) ? '' : m.parameters_not_option({ label, value: v, options: d.options.join(', ') });
    default:
      if ([...String(text ?? '')].length > d.maxLength) return m.parameters_too_long({ label, max: d.maxLength });
      // (Line feed and tab are allowed, as the node allows them.)
      // eslint-disable-next-line no-control-regex
      return /[\u0000-\u0008\u000b-\u001f\u007f]/.test(String(text ?? '')) ? m.parameters_control_chars({ label }) : '';
  }
}

/**
 * The text a value is sent and compared as (numbers trimmed, with a decimal point; strings as typed).
 * @param {ParamDef} d @param {string} text
 */
export function canonical(d, text) {
  if (d.type === 'int' || d.type === 'float') return nodeNumber(text);
  return d.type === 'string' ? String(text ?? '') : String(text ?? '').trim();
}

/**
 * @typedef {{ id: string, label: string | Record<string, string>, unit: string, from: string, to: string }} Change
 */

/** Same value? Numbers by value (60.0 is 60), the rest as text. @param {ParamDef} d @param {string} a @param {string} b */
export function sameValue(d, a, b) {
  if ((d.type === 'int' || d.type === 'float') && a.trim() !== '' && b.trim() !== '' && Number.isFinite(Number(a)) && Number.isFinite(Number(b))) {
    return Number(a) === Number(b);
  }
  return a === b;
}

/**
 * What Save will change: every edited value that differs from the saved one.
 * @param {ParamDef[]} defs @param {Record<string, string>} draft
 * @returns {Change[]}
 */
export function diff(defs, draft) {
  const out = [];
  for (const d of defs) {
    if (!(d.id in draft)) continue;
    const to = canonical(d, draft[d.id]);
    if (!sameValue(d, to, d.value)) out.push({ id: d.id, label: d.label, unit: d.unit, from: d.value, to });
  }
  return out;
}

/** @param {ParamDef[]} defs @param {Record<string, string>} draft @returns {Record<string, string>} id -> problem */
export function problems(defs, draft) {
  /** @type {Record<string, string>} */
  const out = {};
  for (const d of defs) {
    if (!(d.id in draft)) continue;
    const p = validate(d, draft[d.id]);
    if (p) out[d.id] = p;
  }
  return out;
}

/**
 * A parameter's label in what the node says (its English, from the cell file) as the page names it: the cell file's
 * label in the user's language. @param {ParamDef[]} defs @returns {import('../../core/said.js').Rename}
 */
function labels(defs) {
  return (key, value) => {
    if (key !== 'label') return undefined;
    const d = defs.find((x) => (typeof x.label === 'string' ? x.label : x.label.en) === value);
    return d ? cellText(d.label) : undefined;
  };
}

/** What the node said (a message with a code, or without one: its English), in the user's language. */
function said(/** @type {any} */ r, /** @type {ParamDef[]} */ defs) {
  const text = String(r?.message ?? '');
  return typeof r?.code === 'string' && r.code ? saidText(r.code, paramsOf(r.params), text, labels(defs)) : text;
}

/**
 * The node's per-field errors (cell_msgs/FieldError[]) as id -> message, in the user's language.
 * @param {any} r @param {ParamDef[]} [defs]
 */
export function fieldErrors(r, defs = []) {
  /** @type {Record<string, string>} */
  const out = {};
  for (const e of Array.isArray(r?.errors) ? r.errors : []) if (e?.id) out[String(e.id)] = said(e, defs) || m.parameters_invalid();
  return out;
}

/**
 * The set's answer with its message in the user's language (each listed field's error too).
 * @template T @param {T} r @param {ParamDef[]} defs @returns {T}
 */
export function saidAnswer(r, defs) {
  return localized(r, 'code', 'params', labels(defs));
}

// ---- the local draft: an edit made offline (or not yet saved) survives a reload, to review and send later ----

/** @typedef {{ values: Record<string, string>, savedAt: number }} Draft */

/** @param {string | null} user */
export const draftKey = (user) => `cell-ui:parameters-draft:${user ?? ''}`;

/**
 * @param {Pick<Storage, 'getItem'> | null} storage @param {string | null} user
 * @returns {Draft | null}
 */
export function loadDraft(storage, user) {
  try {
    const raw = storage?.getItem(draftKey(user));
    if (!raw) return null;
    const d = JSON.parse(raw);
    if (!d || typeof d.values !== 'object' || !Number.isFinite(d.savedAt)) return null;
    /** @type {Record<string, string>} */
    const values = {};
    for (const [k, v] of Object.entries(d.values)) if (typeof v === 'string') values[k] = v;
    return { values, savedAt: d.savedAt };
  } catch {
    return null;
  }
}

/**
 * Keep the draft (or remove it when empty).
 * @param {Pick<Storage, 'setItem' | 'removeItem'> | null} storage @param {string | null} user
 * @param {Record<string, string>} values @param {number} now
 */
export function storeDraft(storage, user, values, now) {
  try {
    if (!Object.keys(values).length) storage?.removeItem(draftKey(user));
    else storage?.setItem(draftKey(user), JSON.stringify({ values, savedAt: now }));
  } catch {
    /* storage full or disabled: the draft lives only in the page */
  }
}
