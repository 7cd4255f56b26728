import { describe, it, expect } from 'vitest';
import { moduleViews, moduleAction, bulkTargets, stateLabel, summary, STATE_VIEW } from '../../../src/lib/features/modules/logic.js';

const visible = [{ name: 'Simulated cell' }, { name: 'Vision' }, { name: 'Diagnostics' }];
const msg = {
  modules: [
    { name: 'Vision', state: 'incomplete', nodes: ['/vision', '/vision_monitor'], alive: [true, false], launchable: true, target: '', message: 'not running: /vision_monitor' },
    { name: 'Simulated cell', state: 'active', nodes: ['/sim_cell'], alive: [true], launchable: false, target: '', message: '' },
    { name: 'Secret', state: 'active', nodes: ['/x'], alive: [true], launchable: true },
    { name: 'Diagnostics', state: 'transitioning', nodes: ['/system_monitor'], alive: [false], launchable: true, target: 'active' },
  ],
};

describe('module views', () => {
  it('keeps the role\'s modules in the cell file\'s order, with node liveness, and drops the others', () => {
    const v = moduleViews(visible, msg);
    expect(v.map((m) => m.name)).toEqual(['Simulated cell', 'Vision', 'Diagnostics']);
    expect(v[1].nodes).toEqual([{ name: '/vision', alive: true }, { name: '/vision_monitor', alive: false }]);
    expect(v[1].state).toBe('incomplete');
  });
  it('calls a module by the cell file\'s title (one per language, maybe), else by its name', () => {
    const v = moduleViews([{ name: 'Vision', title: { en: 'Vision', fi: 'Konenäkö' } }, { name: 'Diagnostics' }], msg);
    expect(v.map((x) => x.title)).toEqual([{ en: 'Vision', fi: 'Konenäkö' }, 'Diagnostics']);
    expect(v.map((x) => x.name)).toEqual(['Vision', 'Diagnostics']);
  });
  it('says unknown before the node reported a module, and for a state it does not know', () => {
    expect(moduleViews(visible, null).every((m) => m.state === 'unknown')).toBe(true);
    expect(moduleViews([{ name: 'Vision' }], { modules: [{ name: 'Vision', state: 'exploded' }] })[0].state).toBe('unknown');
  });
  it('labels every state in words (colour is never alone), launching and stopping apart', () => {
    for (const s of Object.values(STATE_VIEW)) expect(s.label).toMatch(/\w/);
    const [, , diag] = moduleViews(visible, msg);
    expect(stateLabel(diag)).toBe('Launching…');
    expect(stateLabel({ ...diag, target: 'inactive' })).toBe('Stopping…');
  });
});

describe('launch and stop', () => {
  const [sim, vision, diag] = moduleViews(visible, msg);
  it('refuses while settling, for monitor-only modules, and when there is nothing to do', () => {
    expect(moduleAction(diag, 'launch')).toMatchObject({ ok: false, reason: /settles/ });
    expect(moduleAction(diag, 'stop').ok).toBe(false);
    expect(moduleAction(sim, 'stop')).toMatchObject({ ok: false, reason: /Monitored only/ });
    expect(moduleAction({ ...vision, state: 'active' }, 'launch').ok).toBe(false);
    expect(moduleAction({ ...vision, state: 'inactive' }, 'stop').ok).toBe(false);
  });
  it('allows both on an incomplete module (relaunch the missing node, or stop the rest)', () => {
    expect(moduleAction(vision, 'launch').ok).toBe(true);
    expect(moduleAction(vision, 'stop').ok).toBe(true);
  });
  it('"Launch all" / "Stop all" act on the modules the single buttons would', () => {
    const v = [sim, vision, { ...diag, state: /** @type {const} */ ('inactive') }];
    expect(bulkTargets(v, 'launch').map((m) => m.name)).toEqual(['Vision', 'Diagnostics']);
    expect(bulkTargets(v, 'stop').map((m) => m.name)).toEqual(['Vision']);
  });
  it('counts states for the summary', () => {
    expect(summary(moduleViews(visible, msg))).toMatchObject({ total: 3, active: 1, incomplete: 1, transitioning: 1 });
  });
});
