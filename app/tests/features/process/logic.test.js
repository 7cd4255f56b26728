import { describe, it, expect } from 'vitest';
import {
  processView, controls, needsStartConfirmation, cycleText, fieldAt, formatValue, parseCycles, formatSeconds, startQuestion,
  cycleTimeText, operationText,
} from '../../../src/lib/features/process/logic.js';

const msg = (o = {}) => ({
  state: 'idle', operations: ['pick part', 'place in fixture', 'return home'], current: -1, step: '', step_index: 0,
  step_count: 0, dry_run: false, run_mode: '', cycle: 0, cycles_target: 0, cycles_done: 0, cycle_time_s: 0,
  last_cycle_s: 0, at_start: true, start_configuration: 'home', message: '', ...o,
});

describe('process view and controls', () => {
  it('before the node answers: the cell file\'s operations, nothing can be started', () => {
    const v = processView(null, ['a', 'b']);
    expect(v.state).toBe('unknown');
    expect(v.operations).toEqual(['a', 'b']);
    const c = controls(v, 0);
    expect(c.start).toEqual({ ok: false, reason: 'Waiting for the process node' });
    expect(c.stop.ok).toBe(false);
  });

  it('idle: Start and Run step (with an operation chosen); Pause and Stop do not apply', () => {
    const c = controls(processView(msg()), 1);
    expect(c.start.ok).toBe(true);
    expect(c.step.ok).toBe(true);
    expect(c.toggle).toMatchObject({ label: 'Pause', ok: false });
    expect(c.stop.ok).toBe(false);
    expect(controls(processView(msg()), -1).step).toEqual({ ok: false, reason: 'Choose an operation first' });
    expect(controls(processView(msg()), 7).step.ok).toBe(false);
  });

  it('running: Pause and Stop; no second Start, no Run step, no dry-run change', () => {
    const c = controls(processView(msg({ state: 'running', current: 1 })), 0);
    expect(c.start).toEqual({ ok: false, reason: 'The process is running' });
    expect(c.toggle).toMatchObject({ label: 'Pause', ok: true });
    expect(c.stop.ok).toBe(true);
    expect(c.step.ok).toBe(false);
    expect(c.dryRun.ok).toBe(false);
  });

  it('pausing keeps the toggle off until the step ends; paused turns it into Resume', () => {
    expect(controls(processView(msg({ state: 'pausing' })), 0).toggle).toMatchObject({ label: 'Pause', ok: false, reason: 'Pausing at the end of the step' });
    expect(controls(processView(msg({ state: 'paused' })), 0).toggle).toMatchObject({ label: 'Resume', ok: true });
    expect(controls(processView(msg({ state: 'paused' })), 0).stop.ok).toBe(true);
  });

  it('an error ends the run: Start again is allowed', () => {
    expect(controls(processView(msg({ state: 'error', message: 'protective stop' })), 0).start.ok).toBe(true);
  });

  it('asks before Start only when the robot is away from a named start configuration', () => {
    expect(needsStartConfirmation(processView(msg({ at_start: false })))).toBe(true);
    expect(needsStartConfirmation(processView(msg({ at_start: true })))).toBe(false);
    expect(needsStartConfirmation(processView(msg({ at_start: false, start_configuration: '' })))).toBe(false);
  });

  it('asks in words for one group or several (a start configuration per group)', () => {
    expect(startQuestion('home')).toBe('The robot is not at home. The first move goes there from where the arm is now. Start anyway?');
    expect(startQuestion('')).toMatch(/^The robot is not at its start configuration\./);
    expect(startQuestion('left: home, right: home')).toBe(
      'The robots are not all at their start configurations (left: home, right: home). The first moves go there from where the arms are now. Start anyway?');
  });

  it('cycle text, seconds and the cycles input', () => {
    expect(cycleText(processView(msg()))).toBe('Not started');
    expect(cycleText(processView(msg({ cycle: 2, cycles_target: 5 })))).toBe('Cycle 2 of 5');
    expect(cycleText(processView(msg({ cycle: 3 })))).toBe('Cycle 3');
    expect(formatSeconds(12.34)).toBe('12.3 s');
    expect(formatSeconds(0)).toBe('–');
    expect(formatSeconds(125)).toBe('2 min 5 s');
    expect(parseCycles('')).toBe(0);
    expect(parseCycles(' 3 ')).toBe(3);
    expect(parseCycles('2.5')).toBeNaN();
    expect(parseCycles('-1')).toBeNaN();
  });
});

describe('status fields', () => {
  it('reads dotted paths and indexes, and formats with the unit', () => {
    const m = { data: 3, wrench: { force: { x: 1.234 } }, values: [1, 2, 3] };
    expect(fieldAt(m, 'data')).toBe(3);
    expect(fieldAt(m, 'wrench.force.x')).toBe(1.234);
    expect(fieldAt(m, 'values[2]')).toBe(3);
    expect(fieldAt(m, 'nope.deeper')).toBeUndefined();
    expect(formatValue(1.234, 's')).toBe('1.23 s');
    expect(formatValue(3)).toBe('3');
    expect(formatValue(true)).toBe('yes');
    expect(formatValue(undefined, 's')).toBe('–');
  });
});

describe('cycle times with and without pauses', () => {
  it('reads both from the state message (0 when a node does not send them)', () => {
    const v = processView(msg({ cycle_time_s: 12.3, cycle_elapsed_s: 14.1, last_cycle_s: 10.5, last_cycle_elapsed_s: 11 }));
    expect([v.cycleTimeS, v.cycleElapsedS, v.lastCycleS, v.lastCycleElapsedS]).toEqual([12.3, 14.1, 10.5, 11]);
    expect(processView(msg({ cycle_time_s: 3 })).cycleElapsedS).toBe(0);
  });

  it('shows the time with pauses beside the active time only when the two read differently', () => {
    expect(cycleTimeText(12.34, 14.1)).toBe('12.3 s (14.1 s with pauses)');
    expect(cycleTimeText(10.5, 10.52)).toBe('10.5 s');                 // the same to the tenth: one figure
    expect(cycleTimeText(10.5, 0)).toBe('10.5 s');                     // no elapsed field
    expect(cycleTimeText(0, 0)).toBe('–');
    expect(cycleTimeText(59, 75)).toBe('59.0 s (1 min 15 s with pauses)');
  });
});


describe('operationText', () => {
  it("shows an operation's title from the cell file in the user's language, else its name", async () => {
    const { setLocale } = await import('../../../src/lib/paraglide/runtime.js');
    const titles = { 'pick part': { en: 'Pick part', es: 'Recoger pieza' } };
    expect(operationText('pick part', titles)).toBe('Pick part');
    expect(operationText('return home', titles)).toBe('return home');
    expect(operationText('toString', titles)).toBe('toString');
    setLocale('es', { reload: false });
    try {
      expect(operationText('pick part', titles)).toBe('Recoger pieza');
    } finally {
      setLocale('en', { reload: false });
    }
  });
});
