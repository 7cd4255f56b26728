import { describe, it, expect } from 'vitest';
import { chooserKind, loadChoice, saveChoice, THROTTLE_MS } from '../../../src/lib/features/video/logic.js';

describe('video logic', () => {
  it('segmented buttons for a few streams, a select for many', () => {
    expect(chooserKind(2)).toBe('buttons');
    expect(chooserKind(4)).toBe('buttons');
    expect(chooserKind(5)).toBe('select');
  });
  it('asks for at most 30 frames a second', () => {
    expect(THROTTLE_MS).toBeGreaterThanOrEqual(33);
  });
  it('remembers the shown stream on this device; storage is optional', () => {
    const m = new Map();
    const storage = /** @type {Storage} */ (/** @type {unknown} */ ({ getItem: (/** @type {string} */ k) => m.get(k) ?? null, setItem: (/** @type {string} */ k, /** @type {string} */ v) => m.set(k, v) }));
    expect(loadChoice(storage)).toBe('');
    saveChoice(storage, '/cell/camera/global/image/compressed');
    expect(loadChoice(storage)).toBe('/cell/camera/global/image/compressed');
    saveChoice(storage, '');
    expect(loadChoice(storage)).toBe('/cell/camera/global/image/compressed');
    const broken = /** @type {Storage} */ (/** @type {unknown} */ ({ getItem: () => { throw new Error('denied'); }, setItem: () => { throw new Error('denied'); } }));
    expect(loadChoice(broken)).toBe('');
    expect(() => saveChoice(broken, '/x')).not.toThrow();
    expect(loadChoice(null)).toBe('');
  });
});
