// Loads and validates the cell file: JSON Schema first (the core schema with each feature's section schema
// composed in), then the cross-references a schema cannot express.
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import Ajv2020Module from 'ajv/dist/2020.js';

// ajv is CommonJS: under Node its default import is the class itself.
const Ajv2020 = /** @type {typeof Ajv2020Module.default} */ (/** @type {unknown} */ (Ajv2020Module));
import { REPO_ROOT } from './env.js';

const SCHEMA_PATH = path.join(REPO_ROOT, 'config/cell.schema.json');

export class CellConfigError extends Error {
  /** @param {string} file @param {string[]} problems */
  constructor(file, problems) {
    super(`${file}: invalid cell file\n${problems.map((p) => `  - ${p}`).join('\n')}`);
    this.file = file;
    this.problems = problems;
  }
}

/** @type {WeakMap<object[], import('ajv').ValidateFunction>} */
const validators = new WeakMap();

/**
 * The core schema with every feature's section schema under its id.
 * @param {import('../features/feature.js').Feature[]} features
 */
export function composeSchema(features) {
  const core = JSON.parse(fs.readFileSync(SCHEMA_PATH, 'utf8'));
  for (const f of features) {
    if (!f.schema) continue;
    if (core.properties[f.id]) throw new Error(`feature "${f.id}" clashes with the core schema's section of that name`);
    core.properties[f.id] = f.schema;
  }
  return core;
}

/** @param {import('../features/feature.js').Feature[]} features */
function getValidator(features) {
  let v = validators.get(features);
  if (!v) {
    const ajv = new Ajv2020({ allErrors: true, strict: true, allowUnionTypes: true });
    v = ajv.compile(composeSchema(features));
    validators.set(features, v);
  }
  return v;
}

/** JSON-pointer-ish path "/roles/operator/pages/2" as "roles.operator.pages[2]" for humans. */
function humanPath(pointer) {
  if (!pointer) return '(root)';
  return pointer.split('/').slice(1).map((s) => (/^\d+$/.test(s) ? `[${s}]` : `.${s}`)).join('').replace(/^\./, '');
}

/** @param {any} err */
function describe(err) {
  const where = humanPath(err.instancePath);
  if (err.keyword === 'additionalProperties') return `${where}: unknown field "${err.params.additionalProperty}"`;
  if (err.keyword === 'required') return `${where}: missing field "${err.params.missingProperty}"`;
  if (err.keyword === 'enum') return `${where}: must be one of ${err.params.allowedValues.join(', ')}`;
  if (err.keyword === 'false schema') return `${where}: not allowed here`; // e.g. `min` on a bool parameter
  return `${where}: ${err.message}`;
}

// ------------------------------------------------------------------------------------------ error reduction
// ajv (allErrors) reports a value that fits none of a oneOf/anyOf's branches with every branch's errors and then the
// combinator's own: one typo in a process step is 26 lines (`missing field "move_relative"`, `unknown field
// "move_named"`, ...). specificErrors keeps the branch the value was meant to be (its type, its kind's key such as
// `move_named`, the most keys it declares) and that branch's errors only; with no such branch, one line saying
// which kinds there are. An if/then rule's own "must match "then" schema" goes when its then/else errors are there.

/** @param {any} root @param {string} pointer "#/a/b" (schemaPath: URI-encoded) or "/a/b" (instancePath) */
function atPointer(root, pointer, uri = false) {
  let node = root;
  for (const raw of pointer.replace(/^#/, '').split('/').slice(1)) {
    let key = raw;
    if (uri) {
      try {
        key = decodeURIComponent(raw);
      } catch {
        return undefined;
      }
    }
    key = key.replace(/~1/g, '/').replace(/~0/g, '~');
    if (node === null || typeof node !== 'object' || !Object.hasOwn(node, key)) return undefined;
    node = node[key];
  }
  return node;
}

/** @param {unknown} v */
function jsonType(v) {
  if (v === null) return 'null';
  if (Array.isArray(v)) return 'array';
  if (typeof v === 'number') return Number.isInteger(v) ? 'integer' : 'number';
  return typeof v;
}

/** @param {any} branch @returns {string[] | null} the JSON types a branch takes (null: any) */
function branchTypes(branch) {
  if (branch.type !== undefined) return [].concat(branch.type);
  return branch.properties || branch.required ? ['object'] : null;
}

/** @param {any} branch @param {unknown} data */
function fitsType(branch, data) {
  const types = branchTypes(branch);
  const t = jsonType(data);
  return !types || types.includes(t) || (t === 'integer' && types.includes('number'));
}

const isObject = (/** @type {unknown} */ v) => jsonType(v) === 'object';
const quoted = (/** @type {string[]} */ names) => names.map((n) => `"${n}"`).join(', ');

/**
 * Which branch of a failed oneOf/anyOf the value was meant to match: {pick} its index, or {lines} what to say
 * instead ([] : keep ajv's own error).
 * @param {any[]} branches @param {unknown} data @param {boolean} several more than one branch passed (oneOf)
 * @returns {{ pick?: number, lines: { message: string, property?: string }[] }}
 */
function chooseBranch(branches, data, several) {
  const fitting = branches.map((_, i) => i).filter((i) => fitsType(branches[i], data));
  if (!fitting.length) {
    const types = [...new Set(branches.flatMap((b) => branchTypes(b) || []))];
    return { lines: types.length ? [{ message: `must be ${types.join(' or ')}` }] : [] };
  }
  if (fitting.length === 1 && !several) return { pick: fitting[0], lines: [] };
  if (!isObject(data)) return { lines: [] };
  const obj = /** @type {Record<string, unknown>} */ (data);
  const kind = (/** @type {number} */ i) => branches[i].required?.[0];
  const keyed = fitting.filter((i) => kind(i) !== undefined && Object.hasOwn(obj, kind(i)));
  if (keyed.length > 1) return { lines: [{ message: `only one of ${quoted(keyed.map(kind))} is allowed` }] };
  if (several) return { lines: [] };
  if (keyed.length === 1) return { pick: keyed[0], lines: [] };
  const declared = fitting.map((i) => Object.keys(obj).filter((k) => Object.hasOwn(branches[i].properties || {}, k)).length);
  const best = Math.max(...declared);
  if (best > 0 && declared.filter((n) => n === best).length === 1) return { pick: fitting[declared.indexOf(best)], lines: [] };
  if (!fitting.every((i) => kind(i) !== undefined)) return { lines: [] };
  const unknown = Object.keys(obj).filter((k) => fitting.every((i) => branches[i].additionalProperties === false
    && !Object.hasOwn(branches[i].properties || {}, k)));
  return {
    lines: [
      { message: `needs one of the fields ${quoted(fitting.map(kind))}` },
      ...unknown.map((k) => ({ message: '', property: k })),
    ],
  };
}

/**
 * The errors that say what is wrong (see above), in ajv's order, each once.
 * @param {any[]} errors ajv's @param {any} schema the validated schema @param {unknown} doc the validated document
 * @returns {any[]}
 */
export function specificErrors(errors, schema, doc) {
  let list = [...errors];
  const combinators = errors.filter((e) => e.keyword === 'oneOf' || e.keyword === 'anyOf').sort((a, b) => a.schemaPath.length - b.schemaPath.length);
  for (const e of combinators) {
    if (!list.includes(e)) continue; // inside a branch already dropped
    const branches = atPointer(schema, e.schemaPath, true);
    // A branch that is a $ref reports its errors under the referenced schema's path: leave those as they are.
    if (!Array.isArray(branches) || branches.some((b) => !b || typeof b !== 'object' || b.$ref)) continue;
    const at = e.instancePath;
    const own = (/** @type {any} */ x) => x.schemaPath.startsWith(`${e.schemaPath}/`);
    const below = (/** @type {any} */ x) => x.instancePath.startsWith(`${at}/`);
    const choice = chooseBranch(branches, atPointer(doc, at), !!e.params?.passingSchemas);
    if (choice.pick !== undefined) {
      const branch = branches[choice.pick];
      const mine = `${e.schemaPath}/${choice.pick}/`;
      // Errors of a $ref inside a branch carry the $ref's schema path: keep those about a field the branch has.
      const declares = (/** @type {any} */ x) => branch.additionalProperties !== false
        || Object.hasOwn(branch.properties || {}, x.instancePath.slice(at.length + 1).split('/')[0]);
      const kept = list.filter((x) => x !== e && (own(x) ? x.schemaPath.startsWith(mine) : !below(x) || declares(x)));
      if (kept.some((x) => x.instancePath === at || below(x))) list = kept;
      else list = kept.concat(e); // nothing specific left: ajv's own line
    } else if (choice.lines.length) {
      const lines = choice.lines.map((l) => (l.property !== undefined
        ? { instancePath: at, schemaPath: e.schemaPath, keyword: 'additionalProperties', params: { additionalProperty: l.property }, message: '' }
        : { instancePath: at, schemaPath: e.schemaPath, keyword: e.keyword, params: {}, message: l.message }));
      const index = list.indexOf(e);
      list = [...list.slice(0, index).filter((x) => !own(x) && !below(x)), ...lines, ...list.slice(index + 1).filter((x) => !own(x) && !below(x))];
    }
  }
  // "must match "then" schema" repeats what the then/else errors under it say.
  list = list.filter((x) => x.keyword !== 'if' || !list.some((y) => y !== x && y.keyword !== 'if'
    && (y.instancePath === x.instancePath || y.instancePath.startsWith(`${x.instancePath}/`))));
  return list;
}

/**
 * Parse + validate a cell document.
 * @param {unknown} doc @param {string} file @param {import('../features/feature.js').Feature[]} features
 * @returns {import('./cell-types.js').Cell}
 */
export function validateCell(doc, file, features) {
  const validate = getValidator(features);
  if (!validate(doc)) {
    // Only the specific errors are useful: a oneOf/anyOf's other branches and its own line just repeat them.
    throw new CellConfigError(file, [...new Set(specificErrors(validate.errors, validate.schema, doc).map(describe))]);
  }
  const cell = /** @type {any} */ (doc);
  const problems = [];
  const pageIds = new Set(cell.pages.map((p) => p.id));
  if (pageIds.size !== cell.pages.length) problems.push('pages: page ids must be unique');
  const feature = (id) => features.find((f) => f.id === id);
  cell.pages.forEach((p, i) => {
    const f = feature(p.id);
    if (!f) problems.push(`pages[${i}]: no feature "${p.id}" (known: ${features.map((x) => x.id).join(', ')})`);
    else if ((f.sectionRequired ?? !!f.schema) && cell[p.id] === undefined) problems.push(`pages[${i}]: page "${p.id}" needs the "${p.id}" section`);
  });
  for (const [role, def] of Object.entries(cell.roles)) {
    def.pages.forEach((p, i) => {
      if (!pageIds.has(p)) problems.push(`roles.${role}.pages[${i}]: unknown page "${p}"`);
    });
    (def.commands || []).forEach((c, i) => {
      const f = feature(c);
      if (!def.pages.includes(c)) problems.push(`roles.${role}.commands[${i}]: "${c}" is not one of the role's pages`);
      else if (f && !f.commands && !f.motion) problems.push(`roles.${role}.commands[${i}]: feature "${c}" has no commands`);
    });
  }
  const om = cell.operation_mode;
  if (om.initial && !om.modes.includes(om.initial)) problems.push(`operation_mode.initial: "${om.initial}" is not in operation_mode.modes`);
  for (const f of features) if (f.check && cell[f.id] !== undefined) problems.push(...f.check(cell[f.id], cell));
  if (problems.length) throw new CellConfigError(file, problems);
  return cell;
}

/** @param {string} file @param {import('../features/feature.js').Feature[]} features */
export function loadCell(file, features) {
  let text;
  try {
    text = fs.readFileSync(file, 'utf8');
  } catch (e) {
    throw new CellConfigError(file, [`cannot read: ${e.code || e.message}`]);
  }
  let doc;
  try {
    doc = yaml.load(text, { filename: file });
  } catch (e) {
    throw new CellConfigError(file, [`YAML syntax: ${e.message.split('\n')[0]}`]);
  }
  return validateCell(doc, file, features);
}
