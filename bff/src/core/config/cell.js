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
  return `${where}: ${err.message}`;
}

/**
 * Parse + validate a cell document.
 * @param {unknown} doc @param {string} file @param {import('../features/feature.js').Feature[]} features
 * @returns {import('./cell-types.js').Cell}
 */
export function validateCell(doc, file, features) {
  const validate = getValidator(features);
  if (!validate(doc)) {
    // Only the deepest errors are useful; anyOf/oneOf parents just repeat them.
    throw new CellConfigError(file, validate.errors.map(describe));
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
