import { describe, it, expect, vi } from 'vitest';
import {
  graphSpecs, readPath, numericPaths, seriesLayout, shortName, messageTimeMs, SeriesBuffer, decimateMinMax, bucketsFor,
  chooseThrottleMs, scatterPoints, formatValue, FrameScheduler, seriesStyle, minDrawGapMs, MIN_THROTTLE_MS, MAX_THROTTLE_MS,
  PX_PER_BUCKET, DRAW_BUDGET,
} from '../../../src/lib/features/sensors/logic.js';

const wrenchGraph = {
  title: 'Wrist wrench', kind: 'time-series', topic: '/cell/wrench', type: 'geometry_msgs/WrenchStamped',
  fields: ['wrench.force.x', 'wrench.force.y', 'wrench.force.z', 'wrench.torque.x', 'wrench.torque.y', 'wrench.torque.z'],
  labels: ['Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz'], limits: { min: -50, max: 50 }, window_s: 10,
};
const tactile = { title: 'Tactile pad', kind: 'scatter', topic: '/cell/tactile', type: 'cell_msgs/Scatter', x: 'x', y: 'y', labels: ['x (mm)', 'y (mm)'], limits: { xmin: 0, xmax: 20, ymin: 0, ymax: 1 } };
const wrench = (/** @type {number[]} */ v, secs = 100, nsecs = 0) => ({
  header: { stamp: { secs, nsecs }, frame_id: 'tool0' },
  wrench: { force: { x: v[0], y: v[1], z: v[2] }, torque: { x: v[3], y: v[4], z: v[5] } },
});

describe('graphSpecs: the cell file graphs as /api/config gives them', () => {
  it('normalises time-series and scatter entries, with limits, labels and the window', () => {
    const [ts, sc] = graphSpecs({ graphs: [wrenchGraph, tactile] });
    expect(ts).toMatchObject({ kind: 'time-series', title: 'Wrist wrench', topic: '/cell/wrench', windowMs: 10_000, limits: { ymin: -50, ymax: 50 } });
    expect(ts.labels).toEqual(['Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz']);
    expect(sc).toMatchObject({ kind: 'scatter', x: 'x', y: 'y', windowMs: 10_000, limits: { xmin: 0, xmax: 20, ymin: 0, ymax: 1 } });
    expect(ts.key).not.toBe(sc.key);
  });
  it('accepts the bare list, drops entries without a topic or with an unknown kind', () => {
    expect(graphSpecs([{ title: 'x' }, { topic: '/a', kind: 'pie' }, { topic: '/b' }]).map((g) => g.topic)).toEqual(['/b']);
    expect(graphSpecs(undefined)).toEqual([]);
    expect(graphSpecs({ graphs: [{ topic: '/c', window_s: 2.5 }] })[0].windowMs).toBe(2500);
  });
});

describe('series from messages', () => {
  it('reads dotted and indexed paths', () => {
    expect(readPath(wrench([1, 2, 3, 4, 5, 6]), 'wrench.torque.y')).toBe(5);
    expect(readPath({ position: [0.1, 0.2] }, 'position[1]')).toBe(0.2);
    expect(readPath({ data: [7, 8] }, 'data.0')).toBe(7);
    expect(readPath({}, 'a.b.c')).toBeUndefined();
  });

  it('legend from the cell file labels; values in field order; NaN for a missing field', () => {
    const [spec] = graphSpecs([wrenchGraph]);
    const l = seriesLayout(spec, wrench([1, 2, 3, 4, 5, 6]));
    expect(l.names).toEqual(['Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz']);
    const out = new Float64Array(6);
    l.read(wrench([-1, -2, -3, -4, -5, -6]), out);
    expect([...out]).toEqual([-1, -2, -3, -4, -5, -6]);
    l.read({ wrench: { force: { x: 1 } } }, out);
    expect(out[0]).toBe(1);
    expect(Number.isNaN(out[5])).toBe(true);
  });

  it("without labels: the message's names (field names, a name list for arrays, every numeric leaf)", () => {
    const [noLabels] = graphSpecs([{ ...wrenchGraph, labels: ['Fx'] }]);
    expect(seriesLayout(noLabels, wrench([1, 2, 3, 4, 5, 6])).names).toEqual(['Fx', 'force.y', 'force.z', 'torque.x', 'torque.y', 'torque.z']);
    const [joints] = graphSpecs([{ topic: '/joint_states', fields: ['position'] }]);
    const js = { header: {}, name: ['shoulder', 'elbow'], position: [0.5, -1] };
    const l = seriesLayout(joints, js);
    expect(l.names).toEqual(['shoulder', 'elbow']);
    const out = new Float64Array(2);
    l.read(js, out);
    expect([...out]).toEqual([0.5, -1]);
    const [all] = graphSpecs([{ topic: '/w' }]);
    expect(seriesLayout(all, wrench([1, 2, 3, 4, 5, 6])).names).toEqual(['force.x', 'force.y', 'force.z', 'torque.x', 'torque.y', 'torque.z']);
    expect(numericPaths({ header: { seq: 1 }, data: new Float32Array([1, 2]), s: 'x', n: 3 })).toEqual(['data', 'n']);
    expect(seriesLayout(graphSpecs([{ topic: '/f', fields: ['data'] }])[0], { data: new Float32Array([1, 2]) }).names).toEqual(['data[0]', 'data[1]']);
    expect(shortName('wrench.force.x')).toBe('force.x');
  });

  it('time: the header stamp when set, else the arrival', () => {
    expect(messageTimeMs(wrench([0, 0, 0, 0, 0, 0], 12, 500_000_000), 99)).toBe(12_500);
    expect(messageTimeMs({ header: { stamp: { secs: 0, nsecs: 0 } } }, 99)).toBe(99);
    expect(messageTimeMs({}, 42)).toBe(42);
  });
});

describe('SeriesBuffer: the rolling window', () => {
  it('keeps the window back from the newest sample, grows past its capacity, restarts when time goes back', () => {
    const b = new SeriesBuffer(2, 1000, 8);
    for (let t = 0; t <= 3000; t += 10) b.push(t, [t, -t]);
    expect(b.newest).toBe(3000);
    expect(b.timeAt(0)).toBe(2000);
    expect(b.length).toBe(101);
    expect(b.cap).toBeGreaterThanOrEqual(101);
    expect(b.valueAt(1, b.length - 1)).toBe(-3000);
    b.push(10, [1, 1]); // a restarted publisher
    expect(b.length).toBe(1);
    expect(b.newest).toBe(10);
  });
});

describe('decimateMinMax: to the pixels, peaks kept', () => {
  /** 100 Hz for 10 s: 1001 samples of a small sine, with a one-sample spike. */
  function signal() {
    const b = new SeriesBuffer(1, 10_000, 64);
    for (let i = 0; i <= 1000; i++) b.push(i * 10, [i === 503 ? 40 : i === 777 ? -35 : Math.sin(i / 20)]);
    return b;
  }

  it('gives at most two points per bucket (so no more points than pixels), in time order, peaks survive', () => {
    const b = signal();
    const width = 360;
    expect(bucketsFor(width)).toBe(width / PX_PER_BUCKET);
    const pts = decimateMinMax(b, 0, 0, 10_000, bucketsFor(width), 10_000);
    expect(pts.length).toBeLessThanOrEqual(width);
    expect(pts.length).toBeLessThanOrEqual((2 * width) / PX_PER_BUCKET);
    expect(pts.length).toBeGreaterThan(width / PX_PER_BUCKET);
    expect(Math.max(...pts.map((p) => p.y))).toBe(40);
    expect(Math.min(...pts.map((p) => p.y))).toBe(-35);
    for (let i = 1; i < pts.length; i++) expect(pts[i].x).toBeGreaterThanOrEqual(pts[i - 1].x);
    // x in seconds relative to the origin (the newest sample): -10..0
    expect(pts[0].x).toBeCloseTo(-10);
    expect(pts.at(-1)?.x).toBeCloseTo(0);
    expect(pts.find((p) => p.y === 40)?.x).toBeCloseTo(-4.97);
  });

  it('min before max when the min came first, and the reverse; one point for a lone sample; NaN skipped', () => {
    const b = new SeriesBuffer(1, 1000);
    [[0, 5], [1, -5], [2, 0], [500, 3], [501, NaN], [502, 9]].forEach(([t, v]) => b.push(t, [v]));
    const pts = decimateMinMax(b, 0, 0, 1000, 2, 0);
    expect(pts.map((p) => p.y)).toEqual([5, -5, 3, 9]);
    const one = new SeriesBuffer(1, 1000);
    one.push(10, [1]);
    expect(decimateMinMax(one, 0, 0, 1000, 10, 10)).toEqual([{ x: 0, y: 1 }]);
  });

  it('reuses the output array and its points', () => {
    const b = signal();
    const out = decimateMinMax(b, 0, 0, 10_000, 50, 10_000);
    const first = out[0];
    const again = decimateMinMax(b, 0, 5000, 10_000, 10, 10_000, out);
    expect(again).toBe(out);
    expect(again[0]).toBe(first);
    expect(again.length).toBeLessThanOrEqual(20);
    expect(again[0].x).toBeGreaterThanOrEqual(-5);
  });

  it('is fast enough for six 100 Hz series every frame', () => {
    const b = new SeriesBuffer(6, 10_000);
    for (let i = 0; i <= 1000; i++) b.push(i * 10, [1, 2, 3, 4, 5, 6].map((k) => Math.sin(i / k)));
    const t0 = performance.now();
    for (let f = 0; f < 60; f++) for (let s = 0; s < 6; s++) decimateMinMax(b, s, 0, 10_000, 180, 10_000);
    expect((performance.now() - t0) / 60).toBeLessThan(8);
  });
});

describe('chooseThrottleMs: what to ask rosbridge for', () => {
  it('about one message per pixel of the window, between 20 and 33 ms', () => {
    expect(chooseThrottleMs(10_000, 350)).toBe(29); // a phone: 10 s on 350 px
    expect(chooseThrottleMs(10_000, 1200)).toBe(MIN_THROTTLE_MS); // a wide screen: 50 Hz at most
    expect(chooseThrottleMs(60_000, 300)).toBe(MAX_THROTTLE_MS); // a long window: still 30 Hz
    expect(chooseThrottleMs(10_000, 0)).toBe(MAX_THROTTLE_MS); // not measured yet
  });
});

describe('minDrawGapMs: a slow phone draws less often', () => {
  it('keeps drawing within its share of the main thread', () => {
    expect(minDrawGapMs(0)).toBe(0); // nothing measured yet
    expect(minDrawGapMs(2)).toBeLessThan(16.7); // a fast device: every frame with new data
    expect(minDrawGapMs(10)).toBe(10 / DRAW_BUDGET); // 10 ms draws: 25 draws a second at most
    expect(1000 / minDrawGapMs(10)).toBeLessThanOrEqual(25);
  });
});

describe('scatter, values, styles', () => {
  it('pairs the x and y lists (shorter wins), caps the count, skips non-finite', () => {
    expect(scatterPoints({ x: [1, 2, 3], y: new Float32Array([4, 5]) }, 'x', 'y')).toEqual([{ x: 1, y: 4 }, { x: 2, y: 5 }]);
    expect(scatterPoints({ x: [1, NaN], y: [1, 2] }, 'x', 'y')).toEqual([{ x: 1, y: 1 }]);
    const big = { x: Array.from({ length: 5000 }, (_, i) => i), y: Array.from({ length: 5000 }, (_, i) => i) };
    expect(scatterPoints(big, 'x', 'y', 1000).length).toBe(1000);
    expect(scatterPoints({}, 'x', 'y')).toEqual([]);
  });
  it('formats values and gives every series its own dash, not only its colour', () => {
    expect(formatValue(1.23456)).toBe('1.235');
    expect(formatValue(-12.3456)).toBe('-12.35');
    expect(formatValue(123.45)).toBe('123.5');
    expect(formatValue(NaN)).toBe('—');
    expect(formatValue(4.1e-5)).toBe('0.000');
    expect(formatValue(2.5e6)).toBe('2.50e+6');
    const dashes = new Set([0, 1, 2, 3, 4, 5].map((i) => seriesStyle(i).dash.join(',')));
    expect(dashes.size).toBe(6);
  });
});

describe('FrameScheduler: at most one draw per frame', () => {
  it('runs each requested function once at the next frame, however often it was requested', () => {
    /** @type {((t: number) => void)[]} */
    const frames = [];
    const s = new FrameScheduler((cb) => frames.push(cb), () => {});
    const a = vi.fn(), b = vi.fn();
    for (let i = 0; i < 10; i++) s.request(a);
    s.request(b);
    expect(frames.length).toBe(1);
    frames.shift()?.(0);
    expect(a).toHaveBeenCalledTimes(1);
    expect(b).toHaveBeenCalledTimes(1);
    // Nothing requested: no frame asked.
    expect(frames.length).toBe(0);
    s.request(a);
    s.cancel(a);
    expect(s.id).toBeNull();
  });
});
