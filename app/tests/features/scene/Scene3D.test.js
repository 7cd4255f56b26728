import { describe, it, expect, vi, beforeEach } from 'vitest';
import { render, screen } from '@testing-library/svelte';
import Scene3D from '../../../src/lib/features/scene/Scene3D.svelte';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { previewFrom } from '../../../src/lib/features/scene/preview.svelte.js';

const section = {
  markers: '/sim/parts', stale_after_s: 1,
  arms: [{ group: 'arm', joints: ['j1'], joint_states: '/joint_states', base: [0, 0, 0, 0], urdf_url: '/api/scene/arms/arm/urdf' }],
};

beforeEach(() => {
  vi.spyOn(ros, 'subscribe').mockImplementation(() => () => {});
});

describe('3D view', () => {
  it('without WebGL says so in place (never a blank box) and subscribes to nothing', async () => {
    // jsdom has no WebGL, as a browser with it turned off.
    render(Scene3D, { section });
    expect(await screen.findByRole('alert', {}, { timeout: 10_000 })).toHaveProperty('textContent', expect.stringMatching(/cannot draw WebGL/));
    expect(ros.subscribe).not.toHaveBeenCalled();
    expect(screen.getByRole('button', { name: 'Reset view' })).toHaveProperty('disabled', true);
    expect(screen.getByRole('table', { name: 'Joint values' })).toBeTruthy();
  }, 20_000); // the first import of three.js: seconds on a busy 2-core machine
});

describe('3D view as a card', () => {
  it('starts only once it comes near the screen (a phone\'s Home opens with it below the fold)', async () => {
    /** @type {((entries: { isIntersecting: boolean }[]) => void)[]} */
    const observers = [];
    vi.stubGlobal('IntersectionObserver', class {
      /** @param {(entries: { isIntersecting: boolean }[]) => void} cb */
      constructor(cb) { observers.push(cb); }
      observe() {}
      disconnect() {}
    });
    try {
      render(Scene3D, { section, compact: true });
      expect(observers).toHaveLength(1);
      // Off screen: nothing started (jsdom has no WebGL, so a started view would say so at once).
      observers[0]([{ isIntersecting: false }]);
      await new Promise((r) => setTimeout(r, 400));
      expect(screen.queryByRole('alert')).toBeNull();
      expect(screen.getByRole('status').textContent).toMatch(/Loading/);
      observers[0]([{ isIntersecting: true }]);
      expect(await screen.findByRole('alert', {}, { timeout: 10_000 })).toHaveProperty('textContent', expect.stringMatching(/cannot draw WebGL/));
    } finally {
      vi.unstubAllGlobals();
    }
  }, 20_000);
});

describe('move preview', () => {
  it('takes the driver\'s answer: joint values by name when reachable; the reason when not', () => {
    expect(previewFrom('arm', 'relative', { reachable: true, message: '', joint_names: ['a', 'b'], positions: [0.1, 0.2], tcp_pose: [1, 2, 3, 0, 0, 0] }))
      .toEqual({ group: 'arm', kind: 'relative', reachable: true, message: '', positions: { a: 0.1, b: 0.2 }, tcpPose: [1, 2, 3, 0, 0, 0] });
    expect(previewFrom('arm', 'pose', { reachable: false, message: 'pose out of reach', joint_names: [], positions: [] }))
      .toEqual({ group: 'arm', kind: 'pose', reachable: false, message: 'pose out of reach', positions: null, tcpPose: null });
    // An answer whose lists do not match is no target to draw.
    expect(previewFrom('arm', 'named', { reachable: true, joint_names: ['a'], positions: [] }).reachable).toBe(false);
  });
});
