// Proof for "an eleventh feature touches none of the others": a feature that exists only in a test
// fixture folder, plus one entry added to a copy of the feature list, gets a menu entry with its own
// icon, a route and its page, for a role whose allowed pages include it. No app file knows about it.
import { describe, it, expect } from 'vitest';
import { render, screen } from '@testing-library/svelte';
import { features } from '../../src/lib/features/index.js';
import { menuPages, routeAccess } from '../../src/lib/core/routing.js';
import SideMenu from '../../src/lib/ui/SideMenu.svelte';
import FeatureView from '../../src/lib/ui/FeatureView.svelte';
import { gaugeEntry } from '../fixtures/features/gauge/entry.js';

const list = [...features, gaugeEntry];
const menuProps = { currentPath: '/gauge', user: { username: 'ann', role: 'tester' }, connState: /** @type {const} */ ('connected'), mode: null };

describe('an eleventh feature', () => {
  it('appears in the menu built from the list, with its icon, for a role that may see it', () => {
    const allowed = [{ id: 'home', title: 'Home' }, { id: 'gauge', title: 'Pressure gauge' }];
    render(SideMenu, { ...menuProps, pages: menuPages(allowed, list) });
    const link = screen.getByRole('link', { name: 'Pressure gauge' });
    expect(link.getAttribute('href')).toBe('/gauge');
    expect(link.getAttribute('data-testid')).toBe('nav-gauge');
    expect(link.getAttribute('aria-current')).toBe('page');
    expect(link.querySelector('[data-testid="gauge-icon"]')).not.toBeNull();
  });

  it('is not in the menu of a role that may not see it, and its URL is denied', () => {
    const allowed = [{ id: 'home', title: 'Home' }];
    render(SideMenu, { ...menuProps, pages: menuPages(allowed, list) });
    expect(screen.queryByTestId('nav-gauge')).toBeNull();
    expect(routeAccess('/gauge', allowed, list).kind).toBe('denied');
  });

  it('its URL loads its page lazily, with the cell-file title and its section of /api/config', async () => {
    const allowed = [{ id: 'gauge', title: 'Pressure gauge' }];
    render(FeatureView, { pathname: '/gauge', allowed, sections: { gauge: { unit: 'bar' } }, features: list });
    expect((await screen.findByTestId('gauge-page')).textContent).toContain('Pressure gauge');
    expect(screen.getByTestId('gauge-section').textContent).toBe('bar');
  });

  it('the app list itself does not know it', () => {
    expect(features.some((f) => f.id === 'gauge')).toBe(false);
    expect(routeAccess('/gauge', [{ id: 'gauge' }]).kind).toBe('not-found');
  });
});
