import { describe, it, expect } from 'vitest';
import { setLocale } from '../../../src/lib/paraglide/runtime.js';
import { cellText } from '../../../src/lib/core/i18n.js';
import { paramDef, byCategory, validate, diff, problems, fieldErrors, saidAnswer, loadDraft, storeDraft, draftKey } from '../../../src/lib/features/parameters/logic.js';

const defs = [
  paramDef({ id: 'approach_height', category: 'Motion', label: 'Approach height', type: 'float', unit: 'mm', has_min: true, min: 5, has_max: true, max: 200, value: '50', default_value: '50' }),
  paramDef({ id: 'parts', category: 'Process', label: 'Parts per cycle', type: 'int', has_min: true, min: 1, has_max: true, max: 20, value: '3', default_value: '3' }),
  paramDef({ id: 'verify', category: 'Process', label: 'Verify placement', type: 'bool', value: 'true', default_value: 'true' }),
  paramDef({ id: 'gripper', category: 'Motion', label: 'Gripper type', type: 'enum', options: ['two-finger', 'vacuum'], value: 'two-finger' }),
  paramDef({ id: 'recipe', category: 'Process', label: 'Recipe name', type: 'string', value: 'demo' }),
];

describe('parameter definitions', () => {
  it('groups by category in first-seen order and keeps limits only where the node set them', () => {
    expect(byCategory(defs).map((g) => [g.category, g.items.map((d) => d.id)])).toEqual([
      ['Motion', ['approach_height', 'gripper']], ['Process', ['parts', 'verify', 'recipe']],
    ]);
    expect(defs[2].min).toBeNull();
    expect(defs[0].max).toBe(200);
  });
});

describe('validation in place', () => {
  it('names the field, the value and the limit with its unit', () => {
    expect(validate(defs[0], '250')).toBe('Approach height: 250 mm is above the maximum 200 mm');
    expect(validate(defs[0], '1')).toBe('Approach height: 1 mm is below the minimum 5 mm');
    expect(validate(defs[0], 'abc')).toBe("Approach height: 'abc' is not a number");
    expect(validate(defs[0], '12.5')).toBe('');
    expect(validate(defs[0], '1e2')).toBe('');
    expect(validate(defs[1], '2.5')).toBe("Parts per cycle: '2.5' is not a whole number");
    expect(validate(defs[1], '21')).toMatch(/above the maximum 20/);
    expect(validate(defs[2], 'yes')).toBe("Verify placement: 'yes' is not true or false");
    expect(validate(defs[3], 'magnet')).toBe("Gripper type: 'magnet' is not one of two-finger, vacuum");
    expect(validate(defs[4], 'a,b "c"')).toBe('');
    expect(validate(defs[4], 'a\u0001b')).toMatch(/control characters/);
    expect(validate(defs[4], 'x'.repeat(201))).toBe('Recipe name: at most 200 characters');
    const short = paramDef({ id: 's', label: 'Short', type: 'string', max_length: 3 });
    expect(validate(short, 'abcd')).toBe('Short: at most 3 characters');
    const tenth = paramDef({ id: 'f', label: 'Force', type: 'float', decimals: 1 });
    expect(validate(tenth, '12.34')).toBe('Force: at most 1 digit after the point');
    expect(validate(tenth, '12.30')).toBe('');
  });
});

describe('the diff before Save', () => {
  it('lists only values that differ from the saved ones, trimmed for numbers', () => {
    const draft = { approach_height: ' 60 ', parts: '3.0', recipe: 'demo ' };
    expect(diff(defs, draft)).toEqual([
      { id: 'approach_height', label: 'Approach height', unit: 'mm', from: '50', to: '60' },
      { id: 'recipe', label: 'Recipe name', unit: '', from: 'demo', to: 'demo ' },
    ]);
    expect(problems(defs, { parts: 'x', verify: 'true' })).toEqual({ parts: "Parts per cycle: 'x' is not a whole number" });
  });
  it('reads the node\'s per-field errors', () => {
    expect(fieldErrors({ errors: [{ id: 'parts', message: 'too many' }] })).toEqual({ parts: 'too many' });
    expect(fieldErrors({})).toEqual({});
  });
});

describe('the local draft', () => {
  it('survives a reload per user, and is removed when empty', () => {
    /** @type {Map<string, string>} */
    const m = new Map();
    const storage = { getItem: (/** @type {string} */ k) => m.get(k) ?? null, setItem: (/** @type {string} */ k, /** @type {string} */ v) => void m.set(k, v), removeItem: (/** @type {string} */ k) => void m.delete(k) };
    storeDraft(storage, 'alice', { parts: '4' }, 1000);
    expect(loadDraft(storage, 'alice')).toEqual({ values: { parts: '4' }, savedAt: 1000 });
    expect(loadDraft(storage, 'bob')).toBeNull();
    storeDraft(storage, 'alice', {}, 2000);
    expect(m.has(draftKey('alice'))).toBe(false);
    m.set(draftKey('alice'), '{not json');
    expect(loadDraft(storage, 'alice')).toBeNull();
  });
});


describe("the cell file's labels and categories per language", () => {
  it('are shown by id, the node\'s English grouping the sections; a plain cell-file string leaves the node\'s', () => {
    const texts = {
      parts: { id: 'parts', label: { en: 'Parts per cycle', es: 'Piezas por ciclo' }, category: { en: 'Process', es: 'Proceso' } },
      verify: { id: 'verify', label: 'Verify placement', category: { en: 'Process', es: 'Proceso' } },
    };
    const ds = [
      paramDef({ id: 'parts', category: 'Process', label: 'Parts per cycle', type: 'int', has_max: true, max: 20, value: '3' }, texts),
      paramDef({ id: 'verify', category: 'Process', label: 'Verify placement', type: 'bool', value: 'true' }, texts),
      paramDef({ id: 'other', category: 'Motion', label: 'Other', type: 'int', value: '1' }, texts),
    ];
    const groups = byCategory(ds);
    expect(groups.map((g) => [g.category, g.items.length])).toEqual([['Process', 2], ['Motion', 1]]);
    setLocale('es', { reload: false });
    try {
      expect(groups.map((g) => cellText(g.title))).toEqual(['Proceso', 'Motion']);
      expect(ds.map((d) => cellText(d.label))).toEqual(['Piezas por ciclo', 'Verify placement', 'Other']);
      expect(validate(ds[0], '99')).toContain('Piezas por ciclo');
    } finally {
      setLocale('en', { reload: false });
    }
  });
});

describe("the node's refusals in the user's language (issue 29)", () => {
  const kv = (/** @type {Record<string, string>} */ o) => Object.entries(o).map(([key, value]) => ({ key, value }));
  const texts = { approach_height: { id: 'approach_height', label: { en: 'Approach height', es: 'Altura de aproximación' } } };
  const ds = [paramDef({ id: 'approach_height', category: 'Motion', label: 'Approach height', type: 'float', unit: 'mm', has_max: true, max: 200.5, value: '50' }, texts),
    paramDef({ id: 'parts', category: 'Process', label: 'Parts per cycle', type: 'int', value: '3' }, texts)];
  // As cell_nodes/parameters says them (test_parameters_logic.py checks the node's side).
  const above = { code: 'parameters.above_max', message: 'Approach height: 250.5 mm is above the maximum 200.5 mm',
    params: { label: 'Approach height', value: '250.5 mm', 'value.code': 'parameters.quantity', 'value.number': '250.5', 'value.unit': 'mm',
      max: '200.5 mm', 'max.code': 'parameters.quantity', 'max.number': '200.5', 'max.unit': 'mm' } };
  const whole = { code: 'parameters.not_whole', message: "Parts per cycle: 'x' is not a whole number", params: { label: 'Parts per cycle', value: "'x'" } };
  const nested = (/** @type {string} */ prefix, /** @type {any} */ s) => ({ [prefix]: s.message, [`${prefix}.code`]: s.code,
    ...Object.fromEntries(Object.entries(s.params).map(([k, v]) => [`${prefix}.${k}`, v])) });
  const answer = {
    success: false, code: 'parameters.nothing_saved', message: `nothing saved: 2 invalid values: ${above.message}; ${whole.message}`,
    params: kv({ count: '2', errors: `${above.message}; ${whole.message}`, 'errors.code': 'parameters.list',
      ...nested('errors.first', above), ...nested('errors.rest', whole) }),
    errors: [{ id: 'approach_height', ...above, params: kv(above.params) }, { id: 'parts', ...whole, params: kv(whole.params) }],
  };

  it("says each field's error and the whole answer in Spanish, with the cell file's label and Spanish numbers", () => {
    setLocale('es', { reload: false });
    try {
      expect(fieldErrors(answer, ds)).toEqual({
        approach_height: 'Altura de aproximación: 250,5 mm supera el máximo 200,5 mm',
        parts: "Parts per cycle: 'x' no es un número entero",
      });
      expect(saidAnswer(answer, ds).message).toBe(
        "no se guardó nada: 2 valores no válidos: Altura de aproximación: 250,5 mm supera el máximo 200,5 mm; Parts per cycle: 'x' no es un número entero");
    } finally {
      setLocale('en', { reload: false });
    }
  });
  it("says what is wrong with the CSV file in Spanish, each problem nested", () => {
    const problem = { code: 'parameters.line_invalid', message: "line 4: Parts per cycle: 'x' is not a whole number; default 3 used",
      params: { line: '4', why: whole.message, default: '3', ...nested('why', whole) } };
    const got = { success: true, code: 'parameters.file_problems_one', message: `1 problem in parameters.csv: ${problem.message}`,
      params: kv({ count: '1', file: 'parameters.csv', problems: problem.message, ...nested('problems', problem) }) };
    setLocale('es', { reload: false });
    try {
      expect(saidAnswer(got, ds).message).toBe("1 problema en parameters.csv: línea 4: Parts per cycle: 'x' no es un número entero; se usa el valor por defecto 3");
    } finally {
      setLocale('en', { reload: false });
    }
  });
  it("keeps the node's English where there is no code, and says the English the node said", () => {
    expect(fieldErrors(answer, ds)).toEqual({ approach_height: above.message, parts: whole.message });
    expect(saidAnswer(answer, ds).message).toBe(answer.message);
    expect(saidAnswer({ success: false, message: 'from an older robot PC' }, ds).message).toBe('from an older robot PC');
  });
});
