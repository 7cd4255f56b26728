// Every user-facing text of the app is in the catalogues (messages/<feature>/<locale>.json) and every language has
// every message. Fails on: a text node or a text attribute written in a component, a prose string literal in a
// component's markup, a key missing (or extra) in a language, a language whose message lacks (or adds) a parameter.
import fs from 'node:fs';
import path from 'node:path';
import { parse } from 'svelte/compiler';
import { describe, expect, it } from 'vitest';

const APP = path.resolve(import.meta.dirname, '..');
const settings = JSON.parse(fs.readFileSync(path.join(APP, 'project.inlang/settings.json'), 'utf8'));
const LOCALES = /** @type {string[]} */ (settings.locales);
const BASE = settings.baseLocale;
const PATTERNS = /** @type {string[]} */ (settings['plugin.inlang.messageFormat'].pathPattern);

// Not words of any language: product and protocol names, units, symbols.
const NOT_TEXT = /^(ROS|URDF|MQTT|TF|RTDE|IK|USB|JSON|YAML|CSV|ID|OK|px|mm|ms|rad|deg|m|s|Hz|fps|kB|MB|x|y|z|rx|ry|rz|°|%|[A-Z]\d?|J\d+)$/;
// Attributes whose static value is shown to (or read out for) the user.
const TEXT_ATTRS = new Set(['aria-label', 'title', 'placeholder', 'alt', 'label', 'aria-description', 'aria-valuetext', 'aria-roledescription']);
// Attributes and props that never hold a user-facing text.
const NON_TEXT_ATTRS = /^(class|style|id|href|src|type|role|name|for|value|min|max|step|inputmode|autocomplete|pattern|accept|method|action|target|rel|lang|dir|form|kind|variant|size|icon|tone|testid|key|mode|state|color|width|height|viewBox|d|fill|stroke.*|transform|points|cx|cy|r|x\d?|y\d?|aria-(controls|live|haspopup|current|expanded|hidden|pressed|selected|describedby|labelledby|orientation|busy|modal|invalid|checked|disabled|atomic|relevant|level|valuemin|valuemax|valuenow)|data-.*|on.*|bind:.*|xmlns.*|tabindex|enterkeyhint|spellcheck|capture|loading|decoding|preserveAspectRatio|stroke-.*|text-anchor|dominant-baseline|font-.*|opacity|clip-path|mask|path|topic|service|feature|group|axis|frame|variant|format)$/;

/** @param {string} s */
const isWords = (s) => {
  const t = s.replace(/\s+/g, ' ').trim();
  if (!/[A-Za-zÀ-ÿ]{2,}/.test(t)) return false;
  return !t.split(/[\s/·:,()–—-]+/).filter(Boolean).every((w) => NOT_TEXT.test(w) || !/[A-Za-z]/.test(w));
};
/** A string literal that reads as prose: several words, or a capitalised word. */
const isProse = (/** @type {string} */ s) => isWords(s) && (/[A-Za-z]\s+[A-Za-z]/.test(s) || /^[A-Z][a-z]/.test(s.trim()) || /[.…!?]$/.test(s.trim()));

/** @param {string} dir @returns {string[]} */
function svelteFiles(dir) {
  return fs.readdirSync(dir, { withFileTypes: true }).flatMap((e) => {
    const p = path.join(dir, e.name);
    if (e.isDirectory()) return e.name === 'paraglide' ? [] : svelteFiles(p);
    return e.name.endsWith('.svelte') ? [p] : [];
  });
}

/**
 * Prose string literals in a template expression. Literals compared against (`state === 'Running'`), used as
 * object keys or member names, are values, not texts.
 * @param {any} node @param {string[]} out @param {any} [parent]
 */
function proseLiterals(node, out, parent) {
  if (!node || typeof node !== 'object') return;
  if (Array.isArray(node)) return node.forEach((n) => proseLiterals(n, out, parent));
  if (node.type === 'Literal' && typeof node.value === 'string') {
    const compared = parent?.type === 'BinaryExpression' && /^(===|!==|==|!=|in)$/.test(parent.operator);
    const key = (parent?.type === 'Property' && parent.key === node) || (parent?.type === 'MemberExpression' && parent.property === node);
    if (!compared && !key && isProse(node.value)) out.push(node.value);
    return;
  }
  if (node.type === 'TemplateLiteral') {
    for (const q of node.quasis) if (isProse(q.value.cooked)) out.push(q.value.cooked);
  }
  for (const [k, v] of Object.entries(node)) {
    if (k === 'loc' || k === 'start' || k === 'end' || k === 'metadata') continue;
    if (v && typeof v === 'object') proseLiterals(v, out, node);
  }
}

/** @param {string} file @returns {string[]} what is written in the file instead of coming from the catalogue */
function hardCodedTexts(file) {
  const src = fs.readFileSync(file, 'utf8');
  const ast = parse(src, { modern: true });
  /** @type {string[]} */
  const found = [];
  /** @param {any} node @param {boolean} inSvg */
  const walk = (node, inSvg) => {
    if (!node || typeof node !== 'object') return;
    if (Array.isArray(node)) return node.forEach((n) => walk(n, inSvg));
    const svg = inSvg || node.name === 'svg';
    if (node.type === 'Text' && !svg && isWords(node.data)) found.push(node.data.trim());
    if (node.type === 'ExpressionTag') proseLiterals(node.expression, found);
    for (const a of node.attributes ?? []) {
      if (a.type !== 'Attribute' || NON_TEXT_ATTRS.test(a.name)) continue;
      const parts = a.value === true ? [] : Array.isArray(a.value) ? a.value : [a.value];
      for (const v of parts) {
        if (v.type === 'Text' && (TEXT_ATTRS.has(a.name) ? isWords(v.data) : isProse(v.data))) found.push(`${a.name}="${v.data}"`);
        if (v.type === 'ExpressionTag') proseLiterals(v.expression, found);
      }
    }
    for (const [k, v] of Object.entries(node)) {
      if (k === 'attributes' || k === 'expression' || k === 'metadata') continue;
      if (k === 'fragment' || k === 'nodes' || k === 'children' || k === 'consequent' || k === 'alternate' || k === 'body' || k === 'fallback' || k === 'pending' || k === 'then' || k === 'catch') walk(v, svg);
    }
  };
  walk(ast.fragment, false);
  return found;
}

/** @param {string} file @returns {Record<string, any>} */
const readJson = (file) => (fs.existsSync(file) ? JSON.parse(fs.readFileSync(file, 'utf8')) : {});

/** The parameter names a message uses ("{name}" in a plain text, declared inputs in a variant message). */
function params(/** @type {any} */ msg) {
  const text = JSON.stringify(msg);
  return [...new Set([...text.matchAll(/\{([A-Za-z_][\w]*)\}/g)].map((x) => x[1]))].sort();
}

describe('the message catalogues', () => {
  it('have every message in every language, with the same parameters, and no message twice', () => {
    /** @type {string[]} */
    const problems = [];
    const seen = new Map();
    for (const pattern of PATTERNS) {
      const file = (/** @type {string} */ l) => path.join(APP, pattern.replace('{locale}', l));
      const base = readJson(file(BASE));
      for (const key of Object.keys(base)) {
        if (key === '$schema') continue;
        if (seen.has(key)) problems.push(`${key}: in ${seen.get(key)} and ${pattern}`);
        seen.set(key, pattern);
      }
      for (const l of LOCALES.filter((x) => x !== BASE)) {
        const other = readJson(file(l));
        for (const [key, msg] of Object.entries(base)) {
          if (key === '$schema') continue;
          if (!(key in other)) problems.push(`${pattern.replace('{locale}', l)}: missing "${key}"`);
          else if (typeof other[key] === 'string' && !other[key].trim()) problems.push(`${pattern.replace('{locale}', l)}: empty "${key}"`);
          else if (params(other[key]).join() !== params(msg).join()) problems.push(`${pattern.replace('{locale}', l)}: "${key}" has parameters ${params(other[key])}, English ${params(msg)}`);
        }
        for (const key of Object.keys(other)) if (key !== '$schema' && !(key in base)) problems.push(`${pattern.replace('{locale}', l)}: "${key}" is not in ${BASE}`);
      }
    }
    expect(problems).toEqual([]);
  });

  // Parses every component: allow for a loaded CI machine.
  it('cover every user-facing text in the components', { timeout: 30_000 }, () => {
    const files = svelteFiles(path.join(APP, 'src'));
    expect(files.length).toBeGreaterThan(50);
    const problems = files.flatMap((f) => hardCodedTexts(f).map((t) => `${path.relative(APP, f)}: ${JSON.stringify(t)}`));
    expect(problems).toEqual([]);
  });

  it('the check finds a hard-coded text, attribute and literal (it would pass with the feature missing otherwise)', () => {
    const tmp = path.join(APP, 'tests', '.i18n-probe.svelte');
    fs.writeFileSync(tmp, `<script>let busy = $state(false);</script>\n<p>Hello there</p><button aria-label="Close menu">{busy ? 'Sending…' : 'Send'}</button><svg><text>ok</text></svg><span class="a b" data-testid="x y"></span>`);
    try {
      expect(hardCodedTexts(tmp)).toEqual(['Hello there', 'aria-label="Close menu"', 'Sending…', 'Send']);
    } finally {
      fs.rmSync(tmp);
    }
  });
});
