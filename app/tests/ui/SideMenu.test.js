import { describe, it, expect, vi } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import SideMenu from '../../src/lib/ui/SideMenu.svelte';
import { menuPages } from '../../src/lib/core/routing.js';

const base = {
  currentPath: '/system',
  cellName: 'Demo cell',
  user: { username: 'ann', role: 'admin' },
  connState: /** @type {const} */ ('connected'),
};

describe('SideMenu', () => {
  it('shows nav entries from config in config order and marks the current page', () => {
    const pages = menuPages([
      { id: 'system', title: 'System' },
      { id: 'home', title: 'Home' },
      { id: 'vision', title: 'Vision' }, // not in this build yet
    ]);
    render(SideMenu, { ...base, pages, mode: 'running' });
    const links = screen.getAllByRole('link');
    expect(links.map((a) => a.getAttribute('data-testid'))).toEqual(['nav-system', 'nav-home']);
    expect(screen.getByTestId('nav-home').getAttribute('href')).toBe('/');
    expect(screen.getByTestId('nav-system').getAttribute('aria-current')).toBe('page');
    expect(screen.getByTestId('nav-home').getAttribute('aria-current')).toBeNull();
    expect(screen.queryByTestId('nav-vision')).toBeNull();
  });

  it("draws each feature's own icon from the list", () => {
    const pages = menuPages([{ id: 'home', title: 'Home' }, { id: 'system', title: 'System' }]);
    render(SideMenu, { ...base, pages, mode: null });
    const d = (/** @type {string} */ id) => screen.getByTestId(id).querySelector('path')?.getAttribute('d');
    expect(d('nav-home')).toBe(pages[0].icon);
    expect(d('nav-system')).toBe(pages[1].icon);
    expect(d('nav-home')).not.toBe(d('nav-system'));
  });

  it('operator sees only Home', () => {
    render(SideMenu, { ...base, pages: menuPages([{ id: 'home', title: 'Home' }]), mode: null });
    expect(screen.getByTestId('nav-home')).toBeTruthy();
    expect(screen.queryByTestId('nav-system')).toBeNull();
  });

  it('shows the mode as a coloured badge and "—" when unknown', () => {
    const { unmount } = render(SideMenu, { ...base, pages: [], mode: 'alarm' });
    const badge = screen.getByTestId('op-mode');
    expect(badge.textContent).toBe('alarm');
    expect(badge.className).toContain('tone-danger');
    unmount();
    render(SideMenu, { ...base, pages: [], mode: null });
    expect(screen.getByTestId('op-mode').textContent).toBe('—');
  });

  it('shows connection state, user and role, and logs out', async () => {
    const onLogout = vi.fn();
    render(SideMenu, { ...base, connState: 'connecting', pages: [], mode: 'idle', onLogout });
    expect(screen.getByTestId('conn-status').textContent).toBe('connecting');
    expect(screen.getByTestId('user-name').textContent).toBe('ann');
    expect(screen.getByTestId('user-role').textContent).toBe('admin');
    await fireEvent.click(screen.getByTestId('logout'));
    expect(onLogout).toHaveBeenCalledTimes(1);
  });
});
