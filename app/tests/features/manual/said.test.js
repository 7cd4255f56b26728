// The driver's state message in the user's language (a locale needs the browser-like environment, not node).
import { describe, it, expect } from 'vitest';
import { pickState, toolLabel } from '../../../src/lib/features/manual/logic.js';
import { setLocale } from '../../../src/lib/paraglide/runtime.js';

describe('the driver state\'s message', () => {
  it("says the driver's message in the user's language from its code, and the driver's English without one", () => {
    const heartbeat = {
      message: 'jog stopped: no heartbeat for 0.2 s', message_code: 'manual.jog_no_heartbeat',
      message_params: [{ key: 'seconds', value: '0.2' }],
    };
    const refused = {
      message: 'jog refused: protective stop is active: clear it first', message_code: 'manual.jog_refused',
      message_params: [{ key: 'why', value: 'protective stop is active: clear it first' }, { key: 'why.code', value: 'manual.protective_stop' }],
    };
    try {
      expect(pickState(heartbeat).message).toBe(heartbeat.message);
      setLocale('es', { reload: false });
      expect(pickState(heartbeat).message).toBe('movimiento manual detenido: sin señal de vida durante 0,2 s');
      expect(pickState(refused).message).toBe('movimiento manual rechazado: la parada de protección está activa: restablézcala primero');
      expect(pickState({ message: 'a newer driver says this', message_code: 'manual.not_in_this_app' }).message).toBe('a newer driver says this');
      expect(pickState({ message: 'plain' }).message).toBe('plain');
      setLocale('de', { reload: false });
      expect(pickState(heartbeat).message).toMatch(/0,2 s/);
    } finally {
      setLocale('en', { reload: false });
    }
  });
});

describe("a tool action's button", () => {
  it("is the cell file's title in the user's language", () => {
    const section = { tools: [{ name: 'gripper', actions: [{ name: 'close', title: { en: 'Close the gripper', de: 'Greifer schließen' } }] }] };
    setLocale('de', { reload: false });
    try {
      expect(toolLabel('gripper', 'close', section)).toBe('Greifer schließen');
    } finally {
      setLocale('en', { reload: false });
    }
    expect(toolLabel('gripper', 'close', section)).toBe('Close the gripper');
  });
});
