// @vitest-environment node
import { describe, it, expect } from 'vitest';
import { commandGate } from '../../src/lib/core/gate.js';

describe('commandGate', () => {
  const base = { offline: false, conn: /** @type {const} */ ('connected'), feature: 'manual', commands: ['manual'], needsLease: true, holdsLease: true };

  it('opens only when online, connected, granted and (for motion) holding the lease', () => {
    expect(commandGate(base)).toEqual({ ok: true, reason: '' });
    expect(commandGate({ ...base, offline: true })).toEqual({ ok: false, reason: 'Offline: commands are unavailable' });
    expect(commandGate({ ...base, conn: 'disconnected' }).reason).toBe('Not connected to ROS');
    expect(commandGate({ ...base, conn: 'connecting' }).reason).toBe('Connecting to ROS…');
    expect(commandGate({ ...base, commands: ['home'] }).reason).toBe('Your role may not send these commands');
    expect(commandGate({ ...base, holdsLease: false }).reason).toBe('Take control first');
    expect(commandGate({ ...base, needsLease: false, holdsLease: false }).ok).toBe(true);
  });

  it('offline wins over every other reason', () => {
    expect(commandGate({ ...base, offline: true, conn: 'disconnected', holdsLease: false }).reason).toMatch(/^Offline/);
  });

  it('tolerates a config without `commands` (the server still enforces grants)', () => {
    expect(commandGate({ ...base, commands: undefined }).ok).toBe(true);
  });

  it('HTTP-only commands ignore the ROS link', () => {
    expect(commandGate({ offline: false }).ok).toBe(true);
  });
});
