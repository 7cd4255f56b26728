import { describe, it, expect, vi } from 'vitest';
import { render, screen } from '@testing-library/svelte';
import FeatureView from '../../src/lib/ui/FeatureView.svelte';
import { gaugeEntry } from '../fixtures/features/gauge/entry.js';

describe('FeatureView (the catch-all route)', () => {
  it('denied: shows access-denied and never loads the page', () => {
    const load = vi.fn(gaugeEntry.load);
    render(FeatureView, { pathname: '/gauge', allowed: [{ id: 'home' }], features: [{ ...gaugeEntry, load }] });
    expect(screen.getByTestId('access-denied').textContent).toContain('Gauge');
    expect(load).not.toHaveBeenCalled();
  });

  it('unknown path: not found', () => {
    render(FeatureView, { pathname: '/nope', allowed: [{ id: 'gauge' }], features: [gaugeEntry] });
    expect(screen.getByTestId('not-found')).toBeTruthy();
  });

  it('a page that fails to load says so', async () => {
    const broken = { ...gaugeEntry, load: () => Promise.reject(new Error('chunk missing')) };
    render(FeatureView, { pathname: '/gauge', allowed: [{ id: 'gauge' }], features: [broken] });
    expect((await screen.findByRole('alert')).textContent).toContain('Could not load this page: chunk missing');
  });

  it('a trailing slash finds the page too', async () => {
    render(FeatureView, { pathname: '/gauge/', allowed: [{ id: 'gauge' }], features: [gaugeEntry] });
    expect(await screen.findByTestId('gauge-page')).toBeTruthy();
  });
});
