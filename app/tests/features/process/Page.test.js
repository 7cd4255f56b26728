// The Process page against a fake rosbridge (tests/fakeRos.js): the cycle times as the process node reports them,
// the active time (paused time excluded) and, when it differs, the time with pauses beside it.
import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, cleanup } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import ProcessPage from '../../../src/lib/features/process/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';
import { ros } from '../../../src/lib/core/connection.svelte.js';
import { lease } from '../../../src/lib/core/lease.svelte.js';
import { lastKnown } from '../../../src/lib/core/lastKnown.js';
import { makeFakeFactory, flush } from '../../fakeRos.js';

const feature = { id: 'process', path: '/process', title: 'Process', icon: '', load: async () => ({ default: ProcessPage }) };

/** @type {ReturnType<typeof makeFakeFactory>} */
let f;

/** @param {object} o */
const state = (o) => ({
  state: 'running', ready: true, operations: ['pick part', 'place in fixture'], current: 0, step: 'Move to home',
  step_index: 0, step_count: 3, dry_run: false, run_mode: 'cycle', cycle: 4, cycles_target: 0, cycles_done: 0,
  cycle_time_s: 0, cycle_elapsed_s: 0, last_cycle_s: 0, last_cycle_elapsed_s: 0, at_start: true,
  start_configuration: 'home', message: 'running', ...o,
});

async function open() {
  session.user = { username: 'ann', role: 'operator' };
  session.config = /** @type {any} */ ({
    cell: { id: 'c', name: 'Demo' }, role: 'operator', pages: [{ id: 'process', title: 'Process' }],
    operation_mode: { topic: '/cell/mode', type: 't', modes: [] }, commands: ['process'],
    features: { process: { operations: ['pick part', 'place in fixture'], status: [] } },
  });
  render(ProcessPage, { feature });
  ros.start();
  await flush();
  f.rosList.at(-1)?.emit('connection');
  flushSync();
}

/** @param {any} msg */
function deliver(msg) {
  for (const t of f.topicsNamed('/cell/process/state').filter((x) => !x.unsubscribed)) t.deliver(msg);
  flushSync();
}

beforeEach(async () => {
  ros.stop();
  f = makeFakeFactory();
  ros.factory = f.factory;
  ros.url = () => 'ws://test/ros';
  session.offline = false;
  vi.stubGlobal('fetch', vi.fn(async () => new Response(JSON.stringify({ holder: null, you: false }), { status: 200 })));
  await lastKnown.clear();
});

afterEach(() => {
  cleanup();
  ros.stop();
  lease.reset();
  vi.unstubAllGlobals();
});

describe('Process page cycle times', () => {
  it('shows the active time and the time with pauses when they differ, the active time alone otherwise', async () => {
    await open();
    await vi.waitFor(() => expect(f.topicsNamed('/cell/process/state').length).toBeGreaterThan(0));
    deliver(state({ cycle_time_s: 12.34, cycle_elapsed_s: 14.1, last_cycle_s: 10.5, last_cycle_elapsed_s: 10.52 }));
    expect(screen.getByText('Cycle time')).toBeTruthy();
    expect(screen.getByTestId('process-cycle-time').textContent).toBe('12.3 s (14.1 s with pauses)');
    expect(screen.getByTestId('process-last-cycle').textContent).toBe('10.5 s');
    deliver(state({ state: 'idle', cycle_time_s: 0, cycle_elapsed_s: 0, last_cycle_s: 12.34, last_cycle_elapsed_s: 80 }));
    expect(screen.getByTestId('process-cycle-time').textContent).toBe('–');
    expect(screen.getByTestId('process-last-cycle').textContent).toBe('12.3 s (1 min 20 s with pauses)');
    // A process node from before the elapsed fields: the one time it has.
    deliver(state({ cycle_time_s: 5, cycle_elapsed_s: undefined, last_cycle_s: 9, last_cycle_elapsed_s: undefined }));
    expect(screen.getByTestId('process-cycle-time').textContent).toBe('5.0 s');
    expect(screen.getByTestId('process-last-cycle').textContent).toBe('9.0 s');
  });
});
