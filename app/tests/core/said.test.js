import { describe, it, expect, afterEach } from 'vitest';
import { setLocale } from '../../src/lib/paraglide/runtime.js';
import { saidKey, saidText, paramsOf, localized } from '../../src/lib/core/said.js';
import { logLines } from '../../src/lib/ui/log.js';
import { processView, processNames } from '../../src/lib/features/process/logic.js';
import { runView } from '../../src/lib/features/routines/logic.js';

/** @param {Array<[string, string]>} kv */
const kvs = (kv) => kv.map(([key, value]) => ({ key, value }));

// As the process node says them (cell_nodes/said.py; the same lines as test_process_logic.py).
const start = {
  text: 'Start: 1 cycle of 3 operations from cycle 1', code: 'process.start_cycles',
  params: kvs([['cycles', '1 cycle'], ['cycles.code', 'process.count_cycle'], ['cycles.count', '1'],
    ['operations', '3 operations'], ['operations.code', 'process.count_operation'], ['operations.count', '3'],
    ['cycle', '1'], ['dry', '']]),
};
const operation = { text: "Operation 'pick part' (cycle 12000)", code: 'process.operation', params: kvs([['operation', 'pick part'], ['cycle', '12000']]) };
const alarm = {
  text: 'the cell went into alarm (alarms): robot.arm.protective_stop: Robot arm: protective stop; the run was stopped',
  code: 'process.reason_alarm_named',
  params: kvs([['source', 'alarms'], ['alarm_id', 'robot.arm.protective_stop'], ['alarm', 'Robot arm: protective stop'],
    ['alarm.code', 'alarm.robot.safety.protective_stop'], ['alarm.group', 'arm']]),
};
const titles = { 'pick part': { en: 'Pick part', es: 'Recoger pieza' } };

afterEach(() => setLocale('en', { reload: false }));

describe('what a node said, in the user\'s language', () => {
  it('keys: the feature, _said_, the rest; an alarm\'s code is the alarms feature\'s', () => {
    expect(saidKey('process.step_move_named')).toBe('process_said_step_move_named');
    expect(saidKey('alarm.robot.safety.protective_stop')).toBe('alarms_code_robot_safety_protective_stop');
  });

  it('English as the node said it; nested texts and plurals in the language; numbers in its format', () => {
    expect(saidText(start.code, paramsOf(start.params), start.text)).toBe(start.text);
    setLocale('es', { reload: false });
    expect(saidText(start.code, paramsOf(start.params), start.text)).toBe('Inicio: 3 operaciones, 1 ciclo, desde el ciclo 1');
    expect(saidText(operation.code, paramsOf(operation.params), operation.text)).toBe('Operación «pick part» (ciclo 12.000)');
    setLocale('fi', { reload: false });
    expect(saidText(start.code, paramsOf(start.params), start.text)).toBe('Käynnistys: 1 jakso, 3 operaatiota, jaksosta 1');
  });

  it('an alarm nested in a process text says the alarm in the language too', () => {
    setLocale('de', { reload: false });
    expect(saidText(alarm.code, paramsOf(alarm.params), alarm.text)).toBe(
      'die Zelle ging in Alarm (alarms): robot.arm.protective_stop: Roboter arm: Schutzstopp: der Roboter hat angehalten; Ursache beheben, dann entsperren; der Lauf wurde gestoppt');
  });

  it('without a code, or with one this app does not know (a newer robot PC), the node\'s English', () => {
    setLocale('es', { reload: false });
    expect(saidText('', {}, 'plain words')).toBe('plain words');
    expect(saidText('process.something_new', { a: '1' }, 'newer words')).toBe('newer words');
    // An unknown nested code: that part in English, the rest in Spanish.
    const p = paramsOf(kvs([['reason', 'a newer reason'], ['reason.code', 'process.newer']]));
    expect(saidText('process.error', p, 'Error: a newer reason')).toBe('Error: a newer reason');
    expect(saidText('process.stop', p, 'Stop: a newer reason')).toBe('Parada: a newer reason');
  });

  it('the process log and state name an operation by its title in the cell file', () => {
    setLocale('es', { reload: false });
    const lines = logLines({ entries: [{ stamp: { secs: 1 }, level: 'info', ...operation }, { stamp: { secs: 2 }, level: 'info', text: 'plain' }] }, 10, processNames(titles));
    expect(lines.map((l) => l.text)).toEqual(['plain', 'Operación «Recoger pieza» (ciclo 12.000)']);
    const v = processView({ state: 'running', step: 'Move to home', step_code: 'process.step_move_named', step_params: kvs([['name', 'home']]),
      message: "operation 'pick part' done", message_code: 'process.done_operation', message_params: kvs([['operation', 'pick part']]) }, [], processNames(titles));
    expect(v.step).toBe('Mover a home');
    expect(v.message).toBe('operación «Recoger pieza» hecha');
  });

  it("a step's own text and note by the cell file's text in the language, a pose-table number kept", () => {
    const texts = [
      { en: 'Lift the part', es: 'Levantar la pieza' },
      { en: 'Pick part {n} again', es: 'Recoger la pieza {n} otra vez' },
      { en: 'approach', es: 'aproximación' },
    ];
    const names = processNames(titles, texts);
    const lift = { step: 'Lift the part', step_code: 'process.step_text', step_params: kvs([['text', 'Lift the part']]) };
    const again = { step: 'Pick part 3 again', step_code: 'process.step_text', step_params: kvs([['text', 'Pick part 3 again']]) };
    const table = {
      step: 'Move to part 2 (approach)', step_code: 'process.step_move_table',
      step_params: kvs([['table', 'part'], ['n', '2'], ['note', ' (approach)'], ['note.code', 'process.step_note'], ['note.note', 'approach']]),
    };
    const other = { step: 'Wipe (1+1)', step_code: 'process.step_text', step_params: kvs([['text', 'Wipe (1+1)']]) };
    expect(processView({ state: 'running', ...lift }, [], names).step).toBe('Lift the part');
    setLocale('es', { reload: false });
    expect(processView({ state: 'running', ...lift }, [], names).step).toBe('Levantar la pieza');
    expect(processView({ state: 'running', ...again }, [], names).step).toBe('Recoger la pieza 3 otra vez');
    expect(processView({ state: 'running', ...table }, [], names).step).toBe('Mover a part 2 (aproximación)');
    // A text the cell file gives in one language only: the node's English.
    expect(processView({ state: 'running', ...other }, [], names).step).toBe('Wipe (1+1)');
  });
});

describe("a service's answer with a code (the manual driver's moves, tool actions, previews)", () => {
  it('its message in the language, every other field as it came; an answer without a code as is', () => {
    const arrived = { success: true, message: 'arrived at home', code: 'manual.arrived_at', params: kvs([['name', 'home']]) };
    expect(localized(arrived)).toEqual(arrived);
    setLocale('es', { reload: false });
    expect(localized(arrived)).toEqual({ ...arrived, message: 'se alcanzó home' });
    const refused = {
      reachable: false, message: 'unknown configuration \'x\' for group arm (it has: home)', code: 'manual.unknown_configuration',
      params: kvs([['name', 'x'], ['group', 'arm'], ['known', 'home']]), positions: [],
    };
    expect(localized(refused).message).toBe('configuración desconocida «x» para el grupo arm (tiene: home)');
    expect(localized(refused).positions).toBe(refused.positions);
    const plain = { success: false, message: 'stopped' };
    expect(localized(plain)).toBe(plain);
    expect(localized(null)).toBe(null);
  });
});

describe("the routines node's run state", () => {
  it("says a failed step with the driver's reason inside, all in the language", () => {
    const failed = {
      state: 'idle', name: 'pick two', message: 'step 2 of 3 (pose x 412.3, y -120.0, z 230.5 mm) failed: protective stop is active: clear it first',
      message_code: 'routines.step_failed',
      message_params: kvs([['step', '2'], ['total', '3'], ['what', 'pose x 412.3, y -120.0, z 230.5 mm'], ['what.code', 'routines.step_pose'],
        ['what.x', '412.3'], ['what.y', '-120.0'], ['what.z', '230.5'], ['why', 'protective stop is active: clear it first'],
        ['why.code', 'manual.protective_stop']]),
    };
    expect(runView(failed).message).toBe(failed.message);
    setLocale('es', { reload: false });
    expect(runView(failed).message).toBe('el paso 2 de 3 (pose x 412,3, y -120,0, z 230,5 mm) falló: la parada de protección está activa: restablézcala primero');
    expect(runView({ state: 'idle', message: 'stopped' }).message).toBe('stopped');
  });
});
