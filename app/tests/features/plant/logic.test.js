// @vitest-environment node
import { describe, it, expect } from 'vitest';
import {
  readPlant, readCell, shiftText, cellName, cellLink, hasAlarm, cellStatus, sortCells, formatClock, formatDuration, formatSince,
  onlineText, formatCycleTime, alarmLine, safetyText, processText, robotText, modulesText, brokerView, countText,
} from '../../../src/lib/features/plant/logic.js';

/** A healthy, online cell; `o` overrides. @param {any} [o] */
const cell = (o = {}) => readCell({
  id: `plant-a/${o.node ?? 'demo-ur5'}`, group: 'plant-a', node: 'demo-ur5', name: 'Demo UR5 cell', url: 'http://10.0.0.5:8080/',
  online: true, since: 1, ros: true, mode: 'running', safety: 'normal', alarms: 0, alarm: 'no active alarm', severity: -1,
  process: 'running', operation: 'Pick part', cycles: 12, last_cycle_s: 8.25,
  robots: [{ group: 'ur5', connected: true, mode: 'RUNNING' }], modules: [{ name: 'vision', state: 'active' }], updated: 1, ...o,
});

// Local times, so the tests hold in any time zone.
const NOW = new Date(2026, 10, 26, 10, 37, 20).getTime();

describe('reading the answer', () => {
  it('types every field and fills what is missing', () => {
    const p = readPlant({ broker: { state: 'down', since: 5, error: 'ECONNREFUSED' }, cells: [{ group: 'g', node: 'n', alarms: 'x', robots: null }] });
    expect(p.broker).toEqual({ state: 'down', since: 5, error: 'ECONNREFUSED' });
    const c = p.cells[0];
    expect(c.id).toBe('g/n');
    expect(c.name).toBe('');
    expect(c.url).toBe('');
    expect(c.online).toBe(false);
    expect(c.alarms).toBe(0);
    expect(c.severity).toBe(-1);
    expect(c.robots).toEqual([]);
    expect(c.ros).toBe(true);
  });

  it('an empty or broken answer is an empty plant with the broker off', () => {
    expect(readPlant(null)).toEqual({ broker: { state: 'off', since: 0, error: '' }, cells: [] });
    expect(readPlant({ cells: 'nope' }).cells).toEqual([]);
  });
});

describe('name and link', () => {
  it('a cell without its birth name is called by its node', () => {
    expect(cellName(cell())).toBe('Demo UR5 cell');
    expect(cellName(cell({ name: '' }))).toBe('demo-ur5');
  });

  it('links only to http(s) URLs; "" and other schemes give no link', () => {
    expect(cellLink('http://10.0.0.5:8080/')).toBe('http://10.0.0.5:8080/');
    expect(cellLink(' https://cell-b.local/ ')).toBe('https://cell-b.local/');
    expect(cellLink('')).toBe('');
    expect(cellLink('javascript:alert(1)')).toBe('');
    expect(cellLink('/relative')).toBe('');
  });
});

describe('cellStatus', () => {
  it('a healthy online cell is ok', () => {
    expect(cellStatus(cell())).toEqual({ status: 'ok', text: 'OK' });
    // Its BFF reports, but not what its ROS side says: not OK.
    expect(cellStatus(cell({ ros: false }))).toEqual({ status: 'offline', text: 'No ROS data' });
    expect(hasAlarm(cell())).toBe(false);
  });

  it('an alarm count is an alarm, with the count', () => {
    expect(cellStatus(cell({ alarms: 2, severity: 1 }))).toEqual({ status: 'alarm', text: '2 active alarms' });
    expect(cellStatus(cell({ alarms: 1, severity: 0 })).text).toBe('1 active alarm');
  });

  it('severity 2 with alarms 0 is still an alarm', () => {
    expect(cellStatus(cell({ alarms: 0, severity: 2 }))).toEqual({ status: 'alarm', text: 'Error alarm' });
  });

  it('severity 1 alone is not an alarm', () => {
    expect(cellStatus(cell({ alarms: 0, severity: 1 })).status).toBe('ok');
  });

  it('a safety state other than normal or "" is an alarm and is named', () => {
    expect(cellStatus(cell({ safety: 'protective stop' }))).toEqual({ status: 'alarm', text: 'Protective stop' });
    expect(cellStatus(cell({ safety: 'emergency stop', alarms: 1 })).text).toBe('1 active alarm · Emergency stop');
    expect(cellStatus(cell({ safety: '' })).status).toBe('ok');
    expect(cellStatus(cell({ safety: 'Normal' })).status).toBe('ok');
  });

  it('offline without alarms is offline; offline with alarms stays an alarm and says offline', () => {
    expect(cellStatus(cell({ online: false }))).toEqual({ status: 'offline', text: 'Offline' });
    expect(cellStatus(cell({ online: false, alarms: 3 }))).toEqual({ status: 'alarm', text: '3 active alarms · offline' });
  });
});

describe('sortCells', () => {
  it('alarms first, then offline, then the rest; by name (node without one) within each', () => {
    const list = [
      cell({ node: 'zeta', name: 'Zeta' }),
      cell({ node: 'off-b', name: 'Bravo', online: false }),
      cell({ node: 'alpha', name: 'Alpha' }),
      cell({ node: 'alm-y', name: 'Yankee', severity: 2 }),
      cell({ node: 'cell-10', name: '' }),
      cell({ node: 'cell-9', name: '' }),
      cell({ node: 'alm-c', name: 'Charlie', alarms: 1 }),
      cell({ node: 'off-a', name: 'Able', online: false }),
      cell({ node: 'off-alm', name: 'Zulu', online: false, alarms: 1 }),
      cell({ node: 'stop', name: 'Delta', safety: 'safeguard stop' }),
    ];
    expect(sortCells(list).map((c) => c.node)).toEqual([
      'alm-c', 'stop', 'alm-y', 'off-alm', // alarms: Charlie, Delta, Yankee, Zulu
      'off-a', 'off-b', // offline: Able, Bravo
      'alpha', 'cell-9', 'cell-10', 'zeta', // ok: Alpha, cell-9 < cell-10 (numeric), Zeta
    ]);
  });

  it('returns a new array and leaves the input as it was', () => {
    const list = [cell({ node: 'b', name: 'B' }), cell({ node: 'a', name: 'A' })];
    const sorted = sortCells(list);
    expect(sorted).not.toBe(list);
    expect(list.map((c) => c.node)).toEqual(['b', 'a']);
    expect(sorted.map((c) => c.node)).toEqual(['a', 'b']);
  });

  it('equal names are ordered by id, so the order is stable across updates', () => {
    const a = cell({ id: 'plant-b/x', node: 'x', name: 'Same' });
    const b = cell({ id: 'plant-a/x', node: 'x', name: 'Same' });
    expect(sortCells([a, b]).map((c) => c.id)).toEqual(['plant-a/x', 'plant-b/x']);
    expect(sortCells([b, a]).map((c) => c.id)).toEqual(['plant-a/x', 'plant-b/x']);
  });
});

describe('times', () => {
  it('formatSince: local clock time and how long ago', () => {
    expect(formatSince(new Date(2026, 10, 26, 10, 32, 0).getTime(), NOW)).toBe('since 10:32 (5 min)');
    expect(formatSince(NOW - 40_000, NOW)).toBe('since 10:36 (40 s)');
    expect(formatSince(new Date(2026, 10, 26, 8, 5).getTime(), NOW)).toBe('since 08:05 (2 h 32 min)');
  });

  it('formatSince: another day shows the date; days once it is long', () => {
    expect(formatSince(new Date(2026, 10, 24, 9, 0).getTime(), NOW)).toBe('since 24 Nov 09:00 (2 d)');
    expect(formatClock(new Date(2026, 10, 25, 23, 59).getTime(), NOW)).toBe('25 Nov 23:59');
  });

  it('formatSince: unknown time gives ""; a clock ahead of now is 0 s', () => {
    expect(formatSince(0, NOW)).toBe('');
    expect(formatSince(NaN, NOW)).toBe('');
    expect(formatSince(NOW + 5000, NOW)).toBe('since 10:37 (0 s)');
  });

  it('formatDuration steps', () => {
    expect(formatDuration(59_999)).toBe('59 s');
    expect(formatDuration(60_000)).toBe('1 min');
    expect(formatDuration(3600_000)).toBe('1 h');
    expect(formatDuration(47 * 3600_000 + 60_000)).toBe('47 h 1 min');
    expect(formatDuration(48 * 3600_000)).toBe('2 d');
  });

  it('onlineText says online or offline, with since when known', () => {
    const since = new Date(2026, 10, 26, 10, 34, 0).getTime();
    expect(onlineText(cell({ since }), NOW)).toBe('Online since 10:34 (3 min)');
    expect(onlineText(cell({ since, online: false }), NOW)).toBe('Offline since 10:34 (3 min)');
    expect(onlineText(cell({ since: 0, online: false }), NOW)).toBe('Offline');
  });

  it('formatCycleTime: one decimal, minutes past a minute, a dash for none', () => {
    expect(formatCycleTime(8.25)).toBe('8.3 s');
    expect(formatCycleTime(12)).toBe('12.0 s');
    expect(formatCycleTime(0.04)).toBe('0.0 s');
    expect(formatCycleTime(59.96)).toBe('1 min 0 s');
    expect(formatCycleTime(125.4)).toBe('2 min 5 s');
    expect(formatCycleTime(0)).toBe('—');
    expect(formatCycleTime(-1)).toBe('—');
    expect(formatCycleTime(/** @type {any} */ (undefined))).toBe('—');
  });
});

describe('card lines', () => {
  it('alarm line: active with the count and the text, or an error without a count, or none', () => {
    expect(alarmLine(cell())).toEqual({ active: false, text: 'No active alarm' });
    expect(alarmLine(cell({ alarms: 2, severity: 2, alarm: 'Gripper lost part' }))).toEqual({ active: true, text: '2 active alarms: Gripper lost part' });
    expect(alarmLine(cell({ alarms: 0, severity: 2, alarm: 'Robot fault' }))).toEqual({ active: true, text: 'Error alarm: Robot fault' });
    expect(alarmLine(cell({ alarms: 1, alarm: '' }))).toEqual({ active: true, text: '1 active alarm' });
  });

  it('safety shows only when not normal', () => {
    expect(safetyText(cell())).toBe('');
    expect(safetyText(cell({ safety: '' }))).toBe('');
    expect(safetyText(cell({ safety: 'protective stop' }))).toBe('Protective stop');
  });

  it('process with its operation, or a dash', () => {
    expect(processText(cell())).toBe('running · Pick part');
    expect(processText(cell({ operation: '' }))).toBe('running');
    expect(processText(cell({ process: '', operation: '' }))).toBe('—');
  });

  it('robots: connected with mode, or not connected', () => {
    expect(robotText({ group: 'ur5', connected: true, mode: 'RUNNING' })).toBe('ur5: connected, RUNNING');
    expect(robotText({ group: 'ur5', connected: true, mode: '' })).toBe('ur5: connected');
    expect(robotText({ group: 'kuka', connected: false, mode: 'RUNNING' })).toBe('kuka: not connected');
  });

  it('modules: how many are active', () => {
    const m = (/** @type {string[]} */ ...states) => states.map((state, i) => ({ name: `m${i}`, state }));
    expect(modulesText(m('active', 'active', 'inactive', 'active'))).toBe('3 of 4 modules active');
    expect(modulesText(m('failed'))).toBe('0 of 1 module active');
    expect(modulesText([])).toBe('');
  });
});

describe('header', () => {
  it('broker states', () => {
    expect(brokerView({ state: 'connected', since: 0, error: '' })).toEqual({ tone: 'ok', text: 'Broker connected' });
    expect(brokerView({ state: 'down', since: 0, error: 'connect ECONNREFUSED 10.0.0.1:1883' }))
      .toEqual({ tone: 'danger', text: 'Broker unreachable: connect ECONNREFUSED 10.0.0.1:1883' });
    expect(brokerView({ state: 'down', since: 0, error: '' }).text).toBe('Broker unreachable');
    expect(brokerView({ state: 'connecting', since: 0, error: '' }).tone).toBe('info');
    expect(brokerView({ state: 'off', since: 0, error: '' }).text).toMatch(/^Broker off/);
  });

  it('counts cells, those with alarms and those offline (an offline cell with alarms counts as an alarm)', () => {
    expect(countText([cell(), cell({ alarms: 1 })])).toBe('2 cells, 1 with alarms');
    expect(countText([cell()])).toBe('1 cell, none with alarms');
    expect(countText([cell(), cell({ online: false }), cell({ online: false, alarms: 2 })])).toBe('3 cells, 1 with alarms, 1 offline');
    expect(countText([])).toBe('0 cells, none with alarms');
  });
});

describe('shiftText', () => {
  it('cycles in the last hour and the share of the shift spent running', () => {
    expect(shiftText(cell({ shift: { cycles_last_hour: 12, running_share: 0.854, observed_s: 7800 } })))
      .toBe('12 cycles in the last hour · running 85 % of 2 h 10 min');
    expect(shiftText(cell({ shift: { cycles_last_hour: 1, running_share: null, observed_s: 0 } }))).toBe('1 cycle in the last hour');
    expect(shiftText(cell())).toBe('');
  });
  it('reads it defensively', () => {
    expect(cell({ shift: { cycles_last_hour: -3, running_share: 7, observed_s: 'x' } }).shift).toEqual({ cycles_last_hour: 0, running_share: 1, observed_s: 0 });
    expect(cell({ shift: 'no' }).shift).toBeNull();
  });
});

