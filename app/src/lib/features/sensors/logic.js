/**
 * The sensors feature's plain logic (no Svelte, no Chart.js, no ROS): what a cell-file graph plots, a rolling
 * window of samples, min/max decimation to the screen's pixels, the rosbridge throttle a screen needs, and one
 * draw per animation frame. Tests import it directly.
 *
 * Cell file (`sensors:`, /api/config `features.sensors.graphs`), one entry per graph:
 *   { title, kind: 'time-series' | 'scatter', topic, type,
 *     fields?: ['wrench.force.x', ...], labels?: ['Fx', ...],          time-series: n named variables
 *     x?: 'x', y?: 'y', labels?: ['x (mm)', 'y (mm)'],                 scatter: an x list and a y list
 *     limits?: { min, max } | { xmin, xmax, ymin, ymax }, window_s? }
 * The title and the labels are the cell file's texts: a string, or one per language ({ en, es, ... }); shown through
 * cellText.
 */
import { cellText, fmtFixed } from '../../core/i18n.js';

export const FEATURE_ID = 'sensors';
/** The rolling window when the cell file gives none. */
export const DEFAULT_WINDOW_S = 10;
/** Throttle bounds (ms between messages, applied by rosbridge per client): 50 Hz at most, 30 Hz at least. */
export const MIN_THROTTLE_MS = 20;
export const MAX_THROTTLE_MS = 33;
/** A graph whose topic has been silent this long is stale. */
export const STALE_AFTER_MS = 2000;

/**
 * @typedef {object} GraphSpec
 * @property {string} key  unique per page (index + topic)
 * @property {CellText} title  the cell file's (the topic when it gives none)
 * @property {'time-series' | 'scatter'} kind
 * @property {string} topic
 * @property {string} type
 * @property {string[]} fields  time-series: the field paths (empty: every numeric field of the message)
 * @property {CellText[]} labels  the cell file's ('' for none)
 * @property {string} x  scatter: the x list's field
 * @property {string} y  scatter: the y list's field
 * @property {{ xmin?: number, xmax?: number, ymin?: number, ymax?: number }} limits
 * @property {number} windowMs
 */

/** @typedef {string | Record<string, string>} CellText  a cell-file text: one for all, or one per language */

/** A cell-file text as given (a non-empty string or a per-language object), else null. @param {unknown} v @returns {CellText | null} */
const cellTextOf = (v) => (typeof v === 'string' ? (v ? v : null) : v && typeof v === 'object' && !Array.isArray(v) ? /** @type {Record<string, string>} */ (v) : null);

/** @param {unknown} v */
const num = (v) => (typeof v === 'number' && Number.isFinite(v) ? v : undefined);

/**
 * The graphs of /api/config `features.sensors` (`{ graphs: [...] }`, or the bare list), normalised; entries
 * without a topic or with an unknown kind are dropped.
 * @param {unknown} section
 * @returns {GraphSpec[]}
 */
export function graphSpecs(section) {
  const list = Array.isArray(section) ? section : Array.isArray(/** @type {any} */ (section)?.graphs) ? /** @type {any} */ (section).graphs : [];
  /** @type {GraphSpec[]} */
  const out = [];
  list.forEach((/** @type {any} */ g, /** @type {number} */ i) => {
    if (!g || typeof g.topic !== 'string' || !g.topic) return;
    const kind = g.kind === 'scatter' ? 'scatter' : g.kind === 'time-series' || g.kind === undefined ? 'time-series' : null;
    if (!kind) return;
    const l = g.limits && typeof g.limits === 'object' ? g.limits : {};
    const limits = kind === 'scatter'
      ? { xmin: num(l.xmin), xmax: num(l.xmax), ymin: num(l.ymin), ymax: num(l.ymax) }
      : { ymin: num(l.ymin ?? l.min), ymax: num(l.ymax ?? l.max) };
    const windowS = num(g.window_s) && g.window_s > 0 ? g.window_s : DEFAULT_WINDOW_S;
    out.push({
      key: `${i}:${g.topic}`,
      title: cellTextOf(g.title) ?? g.topic,
      kind,
      topic: g.topic,
      type: typeof g.type === 'string' ? g.type : '',
      fields: Array.isArray(g.fields) ? g.fields.filter((/** @type {unknown} */ f) => typeof f === 'string' && f) : [],
      labels: Array.isArray(g.labels) ? g.labels.map((/** @type {unknown} */ s) => cellTextOf(s) ?? '') : [],
      x: typeof g.x === 'string' && g.x ? g.x : 'x',
      y: typeof g.y === 'string' && g.y ? g.y : 'y',
      limits,
      windowMs: windowS * 1000,
    });
  });
  return out;
}

/**
 * Read a dotted field path ("wrench.force.x", "position[2]", "data.3") from a message.
 * @param {any} msg @param {string} path
 */
export function readPath(msg, path) {
  let v = msg;
  for (const part of path.split(/[.[\]]+/)) {
    if (part === '') continue;
    if (v === null || v === undefined) return undefined;
    v = v[part];
  }
  return v;
}

/** @param {unknown} v */
const isNumList = (v) => (Array.isArray(v) || ArrayBuffer.isView(v)) && !(v instanceof DataView) && /** @type {ArrayLike<unknown>} */ (v).length > 0 &&
  typeof /** @type {ArrayLike<unknown>} */ (v)[0] === 'number';

/**
 * The numeric leaves of a message (header and strings skipped), as field paths: what a time-series plots when
 * the cell file names no fields.
 * @param {any} msg @param {string} [prefix] @returns {string[]}
 */
export function numericPaths(msg, prefix = '') {
  if (!msg || typeof msg !== 'object') return [];
  /** @type {string[]} */
  const out = [];
  for (const [k, v] of Object.entries(msg)) {
    if (k === 'header' || k === 'layout') continue;
    const p = prefix ? `${prefix}.${k}` : k;
    if (typeof v === 'number') out.push(p);
    else if (isNumList(v)) out.push(p);
    else if (v && typeof v === 'object' && !Array.isArray(v) && !ArrayBuffer.isView(v)) out.push(...numericPaths(v, p));
  }
  return out;
}

/**
 * @typedef {object} SeriesLayout
 * @property {string[]} names  one legend entry per series
 * @property {(msg: any, out: Float64Array) => void} read  fills out[i] with series i (NaN when missing)
 */

/**
 * The series a time-series graph plots from a message: each field is one series, or several when it is a list
 * (named by the message's `name` list when it has one of the same length, e.g. sensor_msgs/JointState, else
 * "field[i]"). Legend names: the cell file's labels first, then the message's names.
 * @param {GraphSpec} spec @param {any} msg  the first message (the layout is fixed by it)
 * @returns {SeriesLayout}
 */
export function seriesLayout(spec, msg) {
  const fields = spec.fields.length ? spec.fields : numericPaths(msg);
  /** @type {{ path: string, index: number | null, name: string }[]} */
  const cols = [];
  for (const f of fields) {
    const v = readPath(msg, f);
    if (isNumList(v)) {
      const n = /** @type {ArrayLike<number>} */ (v).length;
      const names = Array.isArray(msg?.name) && msg.name.length === n ? msg.name : null;
      for (let i = 0; i < n; i++) cols.push({ path: f, index: i, name: names ? String(names[i]) : `${shortName(f)}[${i}]` });
    } else {
      cols.push({ path: f, index: null, name: shortName(f) });
    }
  }
  const names = cols.map((c, i) => cellText(spec.labels[i]) || c.name);
  const getters = cols.map((c) => {
    const parts = c.path.split(/[.[\]]+/).filter(Boolean);
    return (/** @type {any} */ m) => {
      let v = m;
      for (const p of parts) {
        if (v === null || v === undefined) return NaN;
        v = v[p];
      }
      if (c.index !== null) v = v?.[c.index];
      return typeof v === 'number' ? v : NaN;
    };
  });
  return {
    names,
    read: (m, out) => {
      for (let i = 0; i < getters.length; i++) out[i] = getters[i](m);
    },
  };
}

/** "wrench.force.x" -> "force.x": the last two parts name a field well enough in a legend. @param {string} path */
export function shortName(path) {
  const parts = path.split('.').filter(Boolean);
  return parts.slice(-2).join('.');
}

/**
 * A message's time in ms: its header stamp when it has one, else the arrival time.
 * @param {any} msg @param {number} arrivedMs
 */
export function messageTimeMs(msg, arrivedMs) {
  const st = msg?.header?.stamp;
  if (st && typeof st === 'object') {
    const ms = Number(st.secs ?? st.sec ?? 0) * 1000 + Number(st.nsecs ?? st.nanosec ?? 0) / 1e6;
    if (Number.isFinite(ms) && ms > 0) return ms;
  }
  return arrivedMs;
}

/**
 * The rolling window of a time-series: times and n series in a ring that grows as needed; samples older than
 * the window (counted back from the newest) are dropped as new ones come.
 */
export class SeriesBuffer {
  /** @param {number} series @param {number} windowMs @param {number} [capacity] */
  constructor(series, windowMs, capacity = 256) {
    this.n = series;
    this.windowMs = windowMs;
    this.cap = Math.max(8, capacity);
    this.t = new Float64Array(this.cap);
    /** @type {Float64Array[]} */
    this.v = Array.from({ length: series }, () => new Float64Array(this.cap));
    this.head = 0; // index of the oldest sample
    this.length = 0;
  }

  /** The newest sample's time (ms), or NaN when empty. */
  get newest() {
    return this.length ? this.t[(this.head + this.length - 1) % this.cap] : NaN;
  }

  /** @param {number} i  0 = oldest */
  timeAt(i) {
    return this.t[(this.head + i) % this.cap];
  }

  /** @param {number} s @param {number} i */
  valueAt(s, i) {
    return this.v[s][(this.head + i) % this.cap];
  }

  clear() {
    this.head = 0;
    this.length = 0;
  }

  /**
   * Add one sample. A time going back (a restarted publisher, a replayed bag) starts the window afresh.
   * @param {number} tMs @param {ArrayLike<number>} values
   */
  push(tMs, values) {
    if (this.length && tMs < this.newest - 1000) this.clear();
    // Drop what falls out of the window before making room.
    const from = tMs - this.windowMs;
    while (this.length && this.t[this.head] < from) {
      this.head = (this.head + 1) % this.cap;
      this.length--;
    }
    if (this.length === this.cap) this.#grow();
    const at = (this.head + this.length) % this.cap;
    this.t[at] = tMs;
    for (let s = 0; s < this.n; s++) this.v[s][at] = values[s] ?? NaN;
    this.length++;
  }

  #grow() {
    const cap = this.cap * 2;
    const t = new Float64Array(cap);
    const v = this.v.map(() => new Float64Array(cap));
    for (let i = 0; i < this.length; i++) {
      const j = (this.head + i) % this.cap;
      t[i] = this.t[j];
      for (let s = 0; s < this.n; s++) v[s][i] = this.v[s][j];
    }
    this.t = t;
    this.v = v;
    this.cap = cap;
    this.head = 0;
  }
}

/** @typedef {{ x: number, y: number }} Point */

/**
 * Min/max decimation of one series to `buckets` pixel columns over [x0, x1]: each bucket keeps its lowest and
 * its highest sample (in time order), so a one-sample peak survives however many samples share its pixel.
 * At most 2 points per bucket; x is reported in seconds relative to `originMs` (the newest sample: -window..0).
 * NaN values are skipped.
 * @param {{ length: number, timeAt: (i: number) => number, valueAt: (s: number, i: number) => number }} buf
 * @param {number} s  the series
 * @param {number} x0 @param {number} x1  the window in ms (x0 < x1)
 * @param {number} buckets
 * @param {number} originMs
 * @param {Point[]} [out]  reused (its points are overwritten; it is truncated to the result)
 * @returns {Point[]}
 */
export function decimateMinMax(buf, s, x0, x1, buckets, originMs, out = []) {
  const B = Math.max(1, Math.floor(buckets));
  const span = x1 - x0;
  let n = 0;
  /** @param {number} t @param {number} y */
  const emit = (t, y) => {
    const p = out[n];
    if (p) {
      p.x = (t - originMs) / 1000;
      p.y = y;
    } else out[n] = { x: (t - originMs) / 1000, y };
    n++;
  };
  let bucket = -1;
  let minT = 0, minY = Infinity, maxT = 0, maxY = -Infinity, count = 0;
  const flush = () => {
    if (!count) return;
    if (count === 1 || minT === maxT) emit(minT, minY);
    else if (minT < maxT) {
      emit(minT, minY);
      emit(maxT, maxY);
    } else {
      emit(maxT, maxY);
      emit(minT, minY);
    }
  };
  for (let i = 0; i < buf.length; i++) {
    const t = buf.timeAt(i);
    if (t < x0 || t > x1) continue;
    const y = buf.valueAt(s, i);
    if (Number.isNaN(y)) continue;
    const b = span > 0 ? Math.min(B - 1, Math.floor(((t - x0) / span) * B)) : 0;
    if (b !== bucket) {
      flush();
      bucket = b;
      count = 0;
      minY = Infinity;
      maxY = -Infinity;
    }
    count++;
    if (y < minY) { minY = y; minT = t; }
    if (y > maxY) { maxY = y; maxT = t; }
  }
  flush();
  out.length = n;
  return out;
}

/** Pixels per decimation bucket: its min and max make at most 2 points per 4 px, so no more points than pixels. */
export const PX_PER_BUCKET = 4;

/**
 * How many buckets (pixel columns of PX_PER_BUCKET px) a plot of `widthPx` CSS pixels is decimated to: two points
 * (min and max) per bucket, so half as many points as pixels (a phone redraws the chart fast enough).
 * @param {number} widthPx
 */
export const bucketsFor = (widthPx) => Math.max(16, Math.floor((Number(widthPx) || 300) / PX_PER_BUCKET));

/** Share of the main thread the graphs may take drawing: a slow phone draws less often, never less smoothly. */
export const DRAW_BUDGET = 0.25;

/**
 * The least time between two draws of a graph that took `drawMs` to draw (a running mean), so that drawing takes
 * at most DRAW_BUDGET of the main thread: 0 on a fast device (every frame with new data is drawn).
 * @param {number} drawMs
 */
export const minDrawGapMs = (drawMs) => (drawMs > 0 ? drawMs / DRAW_BUDGET : 0);

/**
 * The rosbridge throttle for a time-series: about one message per pixel of the window, kept between
 * 20 ms (50 Hz: the screen draws at most once a frame) and 33 ms (30 Hz: still smooth).
 * @param {number} windowMs @param {number} widthPx  the plot's width in CSS pixels (0: not measured yet)
 */
export function chooseThrottleMs(windowMs, widthPx) {
  if (!(widthPx > 0) || !(windowMs > 0)) return MAX_THROTTLE_MS;
  const perPixel = windowMs / widthPx;
  return Math.round(Math.min(MAX_THROTTLE_MS, Math.max(MIN_THROTTLE_MS, perPixel)));
}

/**
 * The points of a scatter message (an x list and a y list; the shorter one decides), at most `max` of them
 * (evenly picked when there are more).
 * @param {any} msg @param {string} xField @param {string} yField @param {number} [max]
 * @param {Point[]} [out]
 * @returns {Point[]}
 */
export function scatterPoints(msg, xField, yField, max = 2000, out = []) {
  const xs = readPath(msg, xField);
  const ys = readPath(msg, yField);
  const len = isNumList(xs) && isNumList(ys) ? Math.min(xs.length, ys.length) : 0;
  const step = len > max ? len / max : 1;
  let n = 0;
  for (let f = 0; f < len; f += step) {
    const i = Math.floor(f);
    const x = xs[i], y = ys[i];
    if (!Number.isFinite(x) || !Number.isFinite(y)) continue;
    const p = out[n];
    if (p) { p.x = x; p.y = y; } else out[n] = { x, y };
    n++;
  }
  out.length = n;
  return out;
}

/** "12.3", "-0.045", "1.2e+4": a live value as text, about four significant digits. @param {number} v */
export function formatValue(v) {
  if (!Number.isFinite(v)) return '—';
  const a = Math.abs(v);
  if (a < 5e-4) return fmtFixed(0, 3);
  if (a >= 1e5) {
    // "2.50e+6": the mantissa in the user's locale, the exponent as written in code.
    const [mantissa, exponent] = v.toExponential(2).split('e');
    return `${fmtFixed(Number(mantissa), 2)}e${exponent}`;
  }
  return fmtFixed(v, a >= 100 ? 1 : a >= 10 ? 2 : 3);
}

/**
 * Draw at most once per animation frame: `request(fn)` marks `fn` to run at the next frame (the same fn
 * requested many times in one frame runs once). Nothing is drawn while nothing changed.
 */
export class FrameScheduler {
  /**
   * @param {(cb: (t: number) => void) => any} [raf]
   * @param {(id: any) => void} [caf]
   */
  constructor(raf = (cb) => requestAnimationFrame(cb), caf = (id) => cancelAnimationFrame(id)) {
    this.raf = raf;
    this.caf = caf;
    /** @type {Set<() => void>} */
    this.due = new Set();
    /** @type {any} */
    this.id = null;
    this.frames = 0;
  }

  /** @param {() => void} fn */
  request(fn) {
    this.due.add(fn);
    if (this.id === null) this.id = this.raf(() => this.#run());
  }

  /** @param {() => void} fn */
  cancel(fn) {
    this.due.delete(fn);
    if (!this.due.size && this.id !== null) {
      this.caf(this.id);
      this.id = null;
    }
  }

  #run() {
    this.id = null;
    this.frames++;
    const fns = [...this.due];
    this.due.clear();
    for (const fn of fns) {
      try {
        fn();
      } catch (e) {
        console.error(e);
      }
    }
  }
}

/**
 * Line styles: colour AND dash, so series differ without colour too (legend shows both). The colour is the theme's
 * (`token`, app.css; core/theme-colors.js), `color` the light theme's where the stylesheet is not there.
 */
export const SERIES_STYLES = Object.freeze([
  { token: '--chart-1', color: '#dc2626', dash: [] },
  { token: '--chart-2', color: '#16a34a', dash: [8, 4] },
  { token: '--chart-3', color: '#2563eb', dash: [2, 3] },
  { token: '--chart-4', color: '#d97706', dash: [10, 3, 2, 3] },
  { token: '--chart-5', color: '#7c3aed', dash: [4, 4] },
  { token: '--chart-6', color: '#0891b2', dash: [12, 2] },
  { token: '--chart-7', color: '#db2777', dash: [2, 6] },
  { token: '--chart-8', color: '#4b5563', dash: [6, 2, 2, 2] },
]);

/** @param {number} i */
export const seriesStyle = (i) => SERIES_STYLES[i % SERIES_STYLES.length];
