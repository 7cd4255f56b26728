import { describe, it, expect, afterEach } from 'vitest';
import { setLocale } from '../../src/lib/paraglide/runtime.js';
import { saidKey, saidText, paramsOf } from '../../src/lib/core/said.js';
import { logLines } from '../../src/lib/ui/log.js';
import { processView, processNames } from '../../src/lib/features/process/logic.js';

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
});
