import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import { flushSync } from 'svelte';

// Chart.js needs a real canvas: a stand-in records what the page asks of it.
const charts = vi.hoisted(() => /** @type {any[]} */ ([]));
vi.mock('chart.js', () => {
  class Chart {
    /** @param {any} _c @param {any} cfg */
    constructor(_c, cfg) {
      this.config = cfg;
      this.data = cfg.data;
      this.options = cfg.options;
      this.chartArea = { width: 300 };
      /** @type {string[]} */
      this.updates = [];
      this.destroyed = false;
      charts.push(this);
    }
    static register() {}
    /** @param {string} mode */
    update(mode) {
      this.updates.push(mode);
    }
    destroy() {
      this.destroyed = true;
    }
  }
  return { Chart, LineController: {}, LineElement: {}, PointElement: {}, LinearScale: {}, ScatterController: {} };
});

import SensorsPage from '../../../src/lib/features/sensors/Page.svelte';
import { ros } from '../../../src/lib/core/connection.svelte.js';

const feature = { id: 'sensors', path: '/sensors', title: 'Sensors', icon: '', load: async () => ({ default: SensorsPage }) };
const section = {
  graphs: [
    {
      title: 'Wrist wrench', kind: 'time-series', topic: '/cell/wrench', type: 'geometry_msgs/WrenchStamped',
      fields: ['wrench.force.x', 'wrench.force.y', 'wrench.force.z', 'wrench.torque.x', 'wrench.torque.y', 'wrench.torque.z'],
      labels: ['Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz'], limits: { min: -50, max: 50 }, window_s: 10,
    },
    { title: 'Tactile pad', kind: 'scatter', topic: '/cell/tactile', type: 'cell_msgs/Scatter', x: 'x', y: 'y', labels: ['x (mm)', 'y (mm)'], limits: { xmin: 0, xmax: 20, ymin: 0, ymax: 1 } },
  ],
};

/** @type {Map<string, { cb: (m: any) => void, options: any }>} */
let live;
/** @type {((t: number) => void)[]} */
let frames;

/** @param {DocumentVisibilityState} v */
function setVisibility(v) {
  Object.defineProperty(document, 'visibilityState', { value: v, configurable: true });
  document.dispatchEvent(new Event('visibilitychange'));
}

beforeEach(() => {
  charts.length = 0;
  live = new Map();
  frames = [];
  vi.spyOn(ros, 'subscribe').mockImplementation((topic, _type, cb, options) => {
    live.set(topic, { cb, options });
    return () => live.delete(topic);
  });
  vi.stubGlobal('requestAnimationFrame', (/** @type {(t: number) => void} */ cb) => frames.push(cb));
  vi.stubGlobal('cancelAnimationFrame', () => {});
});
afterEach(() => {
  vi.unstubAllGlobals();
  // @ts-ignore back to jsdom's own getter
  delete document.visibilityState;
});

const wrench = (/** @type {number} */ i) => ({
  header: { stamp: { secs: 100 + Math.floor(i / 100), nsecs: (i % 100) * 10_000_000 } },
  wrench: { force: { x: i, y: 1, z: 2 }, torque: { x: 3, y: 4, z: i === 50 ? 99 : 5 } },
});

describe('Sensors page', () => {
  it('one chart per cell-file graph, titles and axis limits from the cell file, animations off', () => {
    render(SensorsPage, { feature, section });
    expect(screen.getByRole('heading', { name: 'Wrist wrench' })).toBeTruthy();
    expect(screen.getByRole('heading', { name: 'Tactile pad' })).toBeTruthy();
    expect(charts.length).toBe(2);
    const [ts, sc] = charts;
    expect(ts.config.type).toBe('line');
    expect(ts.options.animation).toBe(false);
    expect(ts.options.scales.y).toMatchObject({ min: -50, max: 50 });
    expect(ts.options.scales.x).toMatchObject({ min: -10, max: 0 });
    expect(sc.config.type).toBe('scatter');
    expect(sc.options.scales.x).toMatchObject({ min: 0, max: 20, title: { text: 'x (mm)' } });
    expect(sc.options.scales.y.title.text).toBe('y (mm)');
  });

  it('subscribes in CBOR with a throttle suited to the screen; draws once per frame, decimated, with update("none")', () => {
    render(SensorsPage, { feature, section });
    const w = live.get('/cell/wrench');
    expect(w?.options).toMatchObject({ compression: 'cbor', queue_length: 1 });
    expect(w?.options.throttle_rate).toBeGreaterThanOrEqual(20);
    expect(w?.options.throttle_rate).toBeLessThanOrEqual(33);
    for (let i = 0; i < 100; i++) w?.cb(wrench(i));
    flushSync();
    expect(frames.length).toBe(1); // 100 messages, one frame asked
    frames.shift()?.(0);
    const ts = charts[0];
    expect(ts.updates).toContain('none');
    expect(ts.data.datasets.map((/** @type {any} */ d) => d.label)).toEqual(['Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz']);
    const fx = ts.data.datasets[0].data;
    expect(fx.length).toBeLessThanOrEqual(300);
    expect(fx.at(-1)).toEqual({ x: 0, y: 99 });
    expect(Math.max(...ts.data.datasets[5].data.map((/** @type {any} */ p) => p.y))).toBe(99);
    flushSync();
    // The legend names the series with text (and a dash pattern), with the latest values.
    const legend = screen.getByRole('list', { name: 'Wrist wrench legend and latest values' });
    expect(legend.textContent).toContain('Fx');
    expect(legend.textContent).toContain('Tz');
  });

  it('Pause <title> freezes the drawing of that graph only; Resume <title> draws the present', async () => {
    render(SensorsPage, { feature, section });
    const ts = charts[0];
    await fireEvent.click(screen.getByRole('button', { name: 'Pause Wrist wrench' }));
    expect(screen.getByRole('button', { name: 'Resume Wrist wrench' }).getAttribute('aria-pressed')).toBe('true');
    expect(screen.getByText('Paused')).toBeTruthy();
    live.get('/cell/wrench')?.cb(wrench(1));
    while (frames.length) frames.shift()?.(0);
    expect(ts.updates.filter((/** @type {string} */ u) => u === 'none').length).toBe(1); // only the legend set-up
    await fireEvent.click(screen.getByRole('button', { name: 'Resume Wrist wrench' }));
    while (frames.length) frames.shift()?.(0);
    expect(ts.data.datasets[0].data.at(-1).y).toBe(1);
    expect(screen.getByRole('button', { name: 'Pause Tactile pad' })).toBeTruthy();
  });

  it('scatter: the latest x and y lists', () => {
    render(SensorsPage, { feature, section });
    live.get('/cell/tactile')?.cb({ x: [1, 2, 3], y: [0.1, 0.2, 0.3] });
    while (frames.length) frames.shift()?.(0);
    expect(charts[1].data.datasets[0].data).toEqual([{ x: 1, y: 0.1 }, { x: 2, y: 0.2 }, { x: 3, y: 0.3 }]);
  });

  it('subscribes only while shown and visible', () => {
    const { unmount } = render(SensorsPage, { feature, section });
    expect([...live.keys()].sort()).toEqual(['/cell/tactile', '/cell/wrench']);
    setVisibility('hidden');
    flushSync();
    expect(live.size).toBe(0);
    expect(screen.getByText(/Paused while the app is hidden/)).toBeTruthy();
    setVisibility('visible');
    flushSync();
    expect(live.size).toBe(2);
    unmount();
    expect(live.size).toBe(0);
    expect(charts.every((c) => c.destroyed)).toBe(true);
  });

  it('says so when the cell has no graphs', () => {
    render(SensorsPage, { feature, section: { graphs: [] } });
    expect(screen.getByTestId('sensors-empty')).toBeTruthy();
    expect(live.size).toBe(0);
  });
});
