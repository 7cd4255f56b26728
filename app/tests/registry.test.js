import { describe, it, expect } from 'vitest';
import { menuPages, routeAccess, safeNext, pageByPath, registry } from '../src/lib/pages/registry.js';

describe('page registry', () => {
  it('knows home and system with their paths', () => {
    expect(registry.map((p) => [p.id, p.path])).toEqual([
      ['home', '/'],
      ['system', '/system'],
    ]);
    expect(pageByPath('/system/')?.id).toBe('system');
  });

  it('menu keeps config order, drops ids this build has no route for, uses config titles', () => {
    const m = menuPages([
      { id: 'system', title: 'System admin' },
      { id: 'modules', title: 'Modules' },
      { id: 'home', title: 'Overview' },
    ]);
    expect(m.map((p) => [p.id, p.title])).toEqual([
      ['system', 'System admin'],
      ['home', 'Overview'],
    ]);
  });

  it('menu is empty without config', () => {
    expect(menuPages(undefined)).toEqual([]);
  });

  it('a page the role may not see is denied; an unknown path is not found', () => {
    const operator = [{ id: 'home', title: 'Home' }];
    expect(routeAccess('/', operator).kind).toBe('page');
    expect(routeAccess('/system', operator)).toMatchObject({ kind: 'denied', entry: { id: 'system' } });
    expect(routeAccess('/system', [...operator, { id: 'system', title: 'S' }]).kind).toBe('page');
    expect(routeAccess('/nope', operator).kind).toBe('not-found');
  });

  it('safeNext only allows same-origin paths', () => {
    expect(safeNext('/system')).toBe('/system');
    expect(safeNext('//evil.example')).toBe('/');
    expect(safeNext('https://evil.example')).toBe('/');
    expect(safeNext('/login?next=/x')).toBe('/');
    expect(safeNext(null)).toBe('/');
  });
});
