// Loads and validates the cell file: JSON Schema first, then the cross-references a schema cannot express.
import fs from 'node:fs';
import path from 'node:path';
import yaml from 'js-yaml';
import Ajv2020 from 'ajv/dist/2020.js';
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

let validator;
function getValidator() {
  if (!validator) {
    const ajv = new Ajv2020({ allErrors: true, strict: true, allowUnionTypes: true });
    validator = ajv.compile(JSON.parse(fs.readFileSync(SCHEMA_PATH, 'utf8')));
  }
  return validator;
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
 * @param {unknown} doc @param {string} file
 * @returns {import('./cell-types.js').Cell}
 */
export function validateCell(doc, file = '<cell>') {
  const validate = getValidator();
  if (!validate(doc)) {
    // Only the deepest errors are useful; anyOf/oneOf parents just repeat them.
    throw new CellConfigError(file, validate.errors.map(describe));
  }
  const cell = /** @type {any} */ (doc);
  const problems = [];
  const pageIds = new Set(cell.pages.map((p) => p.id));
  if (pageIds.size !== cell.pages.length) problems.push('pages: page ids must be unique');
  for (const [role, def] of Object.entries(cell.roles)) {
    def.pages.forEach((p, i) => {
      if (!pageIds.has(p)) problems.push(`roles.${role}.pages[${i}]: unknown page "${p}"`);
    });
  }
  const om = cell.operation_mode;
  if (om.initial && !om.modes.includes(om.initial)) problems.push(`operation_mode.initial: "${om.initial}" is not in operation_mode.modes`);
  (cell.modules || []).forEach((m, i) => (m.roles || []).forEach((r, j) => {
    if (!cell.roles[r]) problems.push(`modules[${i}].roles[${j}]: unknown role "${r}"`);
  }));
  if (problems.length) throw new CellConfigError(file, problems);
  return cell;
}

/** @param {string} file */
export function loadCell(file) {
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
  return validateCell(doc, file);
}
