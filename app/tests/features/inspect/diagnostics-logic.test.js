// @vitest-environment node
// The Diagnostics view's plain logic: the topic, levels, the grouping by component, the worst-first order, the
// summary, the filters, the age of the last array.
import { describe, it, expect } from 'vitest';
import {
  NAMES, DIAG_LEVELS, DIAG_SHOW, DIAG_NO_UPDATE_S, diagLevelName, diagLevel, diagGroupOf, normaliseDiagnostics,
  diagCounts, diagSummaryText, worstDiagLevel, compareDiag, groupDiagnostics, filterDiagnostics, diagAgeText, notLiveView,
} from '../../../src/lib/features/inspect/logic.js';

/** A raw DiagnosticStatus. @param {string} name @param {number} level @param {any} [o] */
const raw = (name, level, o = {}) => ({ level, name, message: `${name} says ${level}`, hardware_id: '', values: [], ...o });
/** Statuses in the page's shape. @param {any[]} list */
const st = (list) => normaliseDiagnostics({ header: { stamp: { secs: 1, nsecs: 0 } }, status: list });
/** @param {import('../../../src/lib/features/inspect/logic.js').DiagGroup[]} groups */
const tree = (groups) => groups.map((g) => [g.name, g.level, g.statuses.map((s) => s.name)]);

describe('the topic', () => {
  it('subscribes to the robot PC\'s aggregated diagnostics', () => {
    expect(NAMES.diagnostics).toEqual({ topic: '/cell/inspect/diagnostics', type: 'diagnostic_msgs/DiagnosticArray' });
  });
});

describe('levels', () => {
  it('reads 0..3 as OK, WARN, ERROR, STALE, and anything else as an error', () => {
    expect([0, 1, 2, 3].map(diagLevelName)).toEqual(['ok', 'warn', 'error', 'stale']);
    expect(diagLevelName('1')).toBe('warn');
    for (const bad of [4, -1, 255, 1.5, NaN, null, undefined, '', 'OK', {}]) expect(diagLevelName(bad)).toBe('error');
  });
  it('has a text for each level (never colour alone)', () => {
    expect(DIAG_LEVELS.map((l) => [l.name, l.value, l.upper])).toEqual([['ok', 0, 'OK'], ['warn', 1, 'WARN'], ['error', 2, 'ERROR'], ['stale', 3, 'STALE']]);
    expect(diagLevel('stale').upper).toBe('STALE');
    expect(diagLevel(/** @type {any} */ ('bogus')).upper).toBe('ERROR');
  });
  it('the worst is error, then stale, then warn, then ok', () => {
    expect(worstDiagLevel([])).toBe('ok');
    expect(worstDiagLevel(['ok', 'ok'])).toBe('ok');
    expect(worstDiagLevel(['ok', 'warn'])).toBe('warn');
    expect(worstDiagLevel(['warn', 'stale', 'ok'])).toBe('stale');
    expect(worstDiagLevel(['stale', 'error', 'warn'])).toBe('error');
    expect(worstDiagLevel(['error', 'stale'])).toBe('error');
  });
});

describe('grouping by component', () => {
  it('splits the name at the first ": "', () => {
    expect(diagGroupOf('vision: camera brightness')).toEqual({ group: 'vision', short: 'camera brightness' });
    expect(diagGroupOf('sim_cell: camera Workbench: left')).toEqual({ group: 'sim_cell', short: 'camera Workbench: left' });
  });
  it('puts names without a component in "other", whole', () => {
    expect(diagGroupOf('battery')).toEqual({ group: 'other', short: 'battery' });
    expect(diagGroupOf('a:b')).toEqual({ group: 'other', short: 'a:b' });
    expect(diagGroupOf(': nothing before')).toEqual({ group: 'other', short: ': nothing before' });
    expect(diagGroupOf('nothing after: ')).toEqual({ group: 'other', short: 'nothing after: ' });
  });
});

describe('the message in the page\'s shape', () => {
  it('fills every field, keeps values in order, drops unnamed statuses, one per name (the later wins)', () => {
    const s = st([
      raw('manual: arm controller', 2, { hardware_id: 'ur5e-1', values: [{ key: 'mode', value: 'RUNNING' }, { key: 'speed', value: 0.25 }, null] }),
      { name: 'bare', level: 7 },
      raw('', 0),
      null,
      raw('vision: camera', 0, { message: 'first' }),
      raw('vision: camera', 3, { message: 'older but later' }),
    ]);
    expect(s).toEqual([
      {
        name: 'manual: arm controller', level: 'error', message: 'manual: arm controller says 2', hardware_id: 'ur5e-1',
        values: [{ key: 'mode', value: 'RUNNING' }, { key: 'speed', value: '0.25' }, { key: '', value: '' }], group: 'manual', short: 'arm controller',
      },
      { name: 'bare', level: 'error', message: '', hardware_id: '', values: [], group: 'other', short: 'bare' },
      { name: 'vision: camera', level: 'stale', message: 'older but later', hardware_id: '', values: [], group: 'vision', short: 'camera' },
    ]);
  });
  it('an array with no status list is empty', () => {
    expect(normaliseDiagnostics({})).toEqual([]);
    expect(normaliseDiagnostics(null)).toEqual([]);
    expect(normaliseDiagnostics({ status: 'x' })).toEqual([]);
  });
});

describe('summary', () => {
  it('counts each level', () => {
    const s = st([raw('a: 1', 0), raw('a: 2', 0), raw('b: 1', 1), raw('c', 3), raw('d', 9), raw('e', 2)]);
    expect(diagCounts(s)).toEqual({ ok: 2, warn: 1, error: 2, stale: 1 });
  });
  it('reads "5 OK · 1 warning · 0 errors · 1 stale"', () => {
    expect(diagSummaryText({ ok: 5, warn: 1, error: 0, stale: 1 })).toBe('5 OK · 1 warning · 0 errors · 1 stale');
    expect(diagSummaryText({ ok: 0, warn: 2, error: 1, stale: 0 })).toBe('0 OK · 2 warnings · 1 error · 0 stale');
    expect(diagSummaryText(diagCounts([]))).toBe('0 OK · 0 warnings · 0 errors · 0 stale');
  });
});

describe('the tree, worst first', () => {
  it('within a group: worst level first, then by name', () => {
    const s = st([raw('v: d', 0), raw('v: c', 1), raw('v: b', 3), raw('v: a', 0), raw('v: e', 2), raw('v: f', 1)]);
    expect([...s].sort(compareDiag).map((x) => x.name)).toEqual(['v: e', 'v: b', 'v: c', 'v: f', 'v: a', 'v: d']);
  });
  it('groups by component, each with its worst level; groups worst first, then by name', () => {
    const s = st([
      raw('vision: camera brightness', 1),
      raw('manual: arm controller', 0),
      raw('sim_cell: camera Workbench', 0),
      raw('battery', 3),
      raw('vision: camera focus', 0),
      raw('alpha: x', 0),
      raw('zeta: y', 2),
      raw('manual: gripper', 0),
    ]);
    expect(tree(groupDiagnostics(s))).toEqual([
      ['zeta', 'error', ['zeta: y']],
      ['other', 'stale', ['battery']],
      ['vision', 'warn', ['vision: camera brightness', 'vision: camera focus']],
      ['alpha', 'ok', ['alpha: x']],
      ['manual', 'ok', ['manual: arm controller', 'manual: gripper']],
      ['sim_cell', 'ok', ['sim_cell: camera Workbench']],
    ]);
  });
  it('leaves its input in order', () => {
    const s = st([raw('b: 1', 0), raw('a: 1', 2)]);
    groupDiagnostics(s);
    expect(s.map((x) => x.name)).toEqual(['b: 1', 'a: 1']);
    expect(groupDiagnostics([])).toEqual([]);
  });
});

describe('filters', () => {
  const s = st([
    raw('vision: camera brightness', 1, { message: 'too dark' }),
    raw('manual: arm controller', 0, { message: 'Running', hardware_id: 'UR5e 20215' }),
    raw('sim_cell: camera Workbench', 3, { message: 'streaming' }),
    raw('robot: drive', 2, { message: 'Over temperature' }),
  ]);
  /** @param {any} f */
  const names = (f) => filterDiagnostics(s, f).map((x) => x.name);

  it('offers All and Problems only', () => {
    expect(DIAG_SHOW.map((o) => [o.id, o.label])).toEqual([['all', 'All'], ['problems', 'Problems only']]);
  });
  it('Problems only keeps WARN, ERROR and STALE', () => {
    expect(names({ show: 'all', text: '' })).toHaveLength(4);
    expect(names({ show: 'problems', text: '' })).toEqual(['vision: camera brightness', 'sim_cell: camera Workbench', 'robot: drive']);
  });
  it('the text matches name, message or hardware id, every word, any case', () => {
    expect(names({ show: 'all', text: 'CAMERA' })).toEqual(['vision: camera brightness', 'sim_cell: camera Workbench']);
    expect(names({ show: 'all', text: 'camera dark' })).toEqual(['vision: camera brightness']);
    expect(names({ show: 'all', text: 'ur5e' })).toEqual(['manual: arm controller']);
    expect(names({ show: 'all', text: 'temperature' })).toEqual(['robot: drive']);
    expect(names({ show: 'problems', text: 'ur5e' })).toEqual([]);
    expect(names({ show: 'all', text: '   ' })).toHaveLength(4);
  });
});

describe('age of the last array', () => {
  it('says how long nothing came once it is 3 s', () => {
    expect(DIAG_NO_UPDATE_S).toBe(3);
    const t = 1_000_000;
    expect(diagAgeText(null, t)).toEqual({ text: '', stale: false });
    expect(diagAgeText(t, t + 400)).toEqual({ text: 'updated just now', stale: false });
    expect(diagAgeText(t, t + 2999)).toEqual({ text: 'updated 2 s ago', stale: false });
    expect(diagAgeText(t, t + 3000)).toEqual({ text: 'no update for 3 s', stale: true });
    expect(diagAgeText(t, t + 45_500)).toEqual({ text: 'no update for 45 s', stale: true });
    expect(diagAgeText(t, t + 5 * 60_000)).toEqual({ text: 'no update for 5 min', stale: true });
    expect(diagAgeText(t, t + 3 * 3600_000)).toEqual({ text: 'no update for 3 h', stale: true });
    // A clock that went back is "just now", not a negative age.
    expect(diagAgeText(t, t - 5000).text).toBe('updated just now');
  });
  it('the not-live notice speaks of the diagnostics', () => {
    expect(notLiveView('disconnected', 'diagnostics')).toEqual({
      title: 'ROS disconnected', text: 'the diagnostics shown may be out of date. They update again once reconnected.',
    });
    expect(notLiveView('offline', 'diagnostics')?.title).toBe('Offline');
    expect(notLiveView(null, 'diagnostics')).toBeNull();
  });
});
