// @vitest-environment node
import { describe, it, expect } from 'vitest';
import { menuPages, routeAccess, safeNext, featureByPath, pageTitle, robotStop } from '../../src/lib/core/routing.js';
import { features } from '../../src/lib/features/index.js';

describe('routing from the feature list', () => {
  it('knows its features with their paths', () => {
    expect(features.map((p) => [p.id, p.path])).toEqual([
      ['home', '/'],
      ['modules', '/modules'],
      ['process', '/process'],
      ['manual', '/manual'],
      ['scene', '/scene'],
      ['sensors', '/sensors'],
      ['video', '/video'],
      ['parameters', '/parameters'],
      ['routines', '/routines'],
      ['alarms', '/alarms'],
      ['recorder', '/recorder'],
      ['inspect', '/inspect'], ['plant', '/plant'],
      ['database', '/database'],
      ['system', '/system'],
    ]);
    expect(featureByPath('/system/')?.id).toBe('system');
    expect(featureByPath('/')?.id).toBe('home');
  });

  it('every entry has an id, a path, a title, an icon and a lazy page', async () => {
    for (const f of features) {
      expect(f.id).toMatch(/^[a-z][a-z0-9_]*$/);
      expect(f.path.startsWith('/')).toBe(true);
      expect(f.title).toBeTruthy();
      expect(['string', 'function']).toContain(typeof f.icon);
      const mod = await f.load();
      expect(typeof mod.default).toBe('function');
    }
    expect(new Set(features.map((f) => f.path)).size).toBe(features.length);
  }, 60_000); // compiles every page (three.js, Chart.js) on a cold cache: seconds each on a busy 2-core machine

  it('menu keeps config order, drops ids this build has no feature for, uses config titles', () => {
    const m = menuPages([
      { id: 'system', title: 'System admin' },
      { id: 'nosuchfeature', title: 'Modules' },
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

  it('the title comes from the cell file when the role sees the page', () => {
    const allowed = [{ id: 'home', title: 'Overview' }];
    expect(pageTitle(routeAccess('/', allowed), allowed)).toBe('Overview');
    expect(pageTitle(routeAccess('/system', allowed), allowed)).toBe('Access denied');
    expect(pageTitle(routeAccess('/x', allowed), allowed)).toBe('Not found');
    expect(pageTitle(routeAccess('/', [{ id: 'home' }]), [{ id: 'home' }])).toBe('Home');
  });

  it('safeNext only allows same-origin paths', () => {
    expect(safeNext('/system')).toBe('/system');
    expect(safeNext('//evil.example')).toBe('/');
    expect(safeNext('https://evil.example')).toBe('/');
    expect(safeNext('/login?next=/x')).toBe('/');
    expect(safeNext(null)).toBe('/');
  });
});

describe('"Stop robot" in the top bar', () => {
  const stop = { service: '/cell/manual/stop', type: 'std_srvs/Trigger' };
  it('is shown for every role that sees any page, one that never moves the robot included', () => {
    // The twin cell's maintenance: no manual, process or routines page, no command that moves an arm.
    const maintenance = { pages: [{ id: 'home' }, { id: 'modules' }, { id: 'alarms' }, { id: 'sensors' }, { id: 'parameters' }], commands: ['modules', 'alarms'], stop };
    expect(robotStop(maintenance)).toEqual(stop);
    // The iiwa operator: the manual page without its commands.
    const iiwaOperator = { pages: [{ id: 'home' }, { id: 'manual' }], commands: ['process', 'alarms'], stop };
    expect(robotStop(iiwaOperator)).toEqual(stop);
    expect(robotStop({ pages: [{ id: 'home' }], stop })).toEqual(stop);
  });
  it('defaults the type to std_srvs/Trigger', () => {
    expect(robotStop({ pages: [{ id: 'home' }], stop: { service: '/s' } })).toEqual({ service: '/s', type: 'std_srvs/Trigger' });
  });
  it('is not shown without a page, or when the cell has no robot stop (or an older answer lacks it)', () => {
    expect(robotStop({ pages: [], stop })).toBeNull();
    expect(robotStop({ pages: [{ id: 'home' }], stop: null })).toBeNull();
    expect(robotStop({ pages: [{ id: 'home' }] })).toBeNull();
    expect(robotStop({ pages: [{ id: 'home' }], stop: { service: '' } })).toBeNull();
    expect(robotStop(null)).toBeNull();
    expect(robotStop(undefined)).toBeNull();
  });
});
