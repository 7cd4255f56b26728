/**
 * Camera images (sensor_msgs/CompressedImage) and the camera view's plain logic.
 * Hot path: subscribed with rosbridge `compression: 'cbor'`, so `data` arrives as a Uint8Array (raw bytes in a
 * binary frame, no base64 in JSON); frameBytes() -> Blob -> createImageBitmap -> canvas (LatestFrameDecoder).
 * imageSrc() (a data: URL from the JSON encoding's base64) stays for callers without CBOR.
 * Also: the frame rate and age (FrameStats, frameStatus), and zoom/pan math for pinch and buttons.
 * A raw (sensor_msgs/Image) stream is never subscribed by the browser: the video service (/cell/video/request)
 * names a JPEG CompressedImage topic at the width the viewer can show (wantedWidth), and /cell/video/status says
 * what is wrong with a stream (streamProblem).
 */
import { m } from '$lib/paraglide/messages.js';
import { cellText, fmtFixed, fmtNumber } from '../core/i18n.js';

/**
 * The image MIME type from CompressedImage.format ("jpeg", "png", "rgb8; jpeg compressed bgr8", ...).
 * @param {unknown} format
 */
export function imageMime(format) {
  const f = typeof format === 'string' ? format.toLowerCase() : '';
  if (f.includes('png')) return 'image/png';
  if (f.includes('webp')) return 'image/webp';
  return 'image/jpeg';
}

/** @param {ArrayLike<number>} bytes */
export function bytesToBase64(bytes) {
  let bin = '';
  const CHUNK = 0x8000; // String.fromCharCode takes the bytes as arguments: keep the call small
  for (let i = 0; i < bytes.length; i += CHUNK) {
    bin += String.fromCharCode.apply(null, Array.from(Array.prototype.slice.call(bytes, i, i + CHUNK)));
  }
  return btoa(bin);
}

/**
 * @param {any} msg  sensor_msgs/CompressedImage
 * @returns {string | null}  a data: URL, or null when the message holds no image
 */
export function imageSrc(msg) {
  const d = msg?.data;
  let b64 = '';
  if (typeof d === 'string') b64 = d;
  else if (d && typeof d.length === 'number' && d.length > 0) b64 = bytesToBase64(d);
  if (!b64) return null;
  return `data:${imageMime(msg?.format)};base64,${b64}`;
}

/** @typedef {'compressed' | 'raw'} StreamType */
/** @typedef {{ name: string, topic: string, type: StreamType }} CameraStream  name: in the user's language */

/**
 * The streams a page may show: /api/config `features.video.streams`, each { name, topic, type }; anything without a
 * topic dropped; a name may be one per language (cellText). type 'raw' is a sensor_msgs/Image topic (asked of the video service); anything else 'compressed'
 * (a CompressedImage topic, subscribed as it is).
 * @param {unknown} streams
 * @returns {CameraStream[]}
 */
export function cameraStreams(streams) {
  if (!Array.isArray(streams)) return [];
  return streams
    .filter((s) => s && typeof s.topic === 'string' && s.topic)
    .map((s) => ({ name: cellText(s.name) || s.topic, topic: s.topic, type: s.type === 'raw' ? 'raw' : 'compressed' }));
}

// ---- raw streams: the video service encodes them to JPEG at the viewer's size ----

export const VIDEO_REQUEST_SERVICE = '/cell/video/request';
export const VIDEO_REQUEST_TYPE = 'cell_msgs/VideoRequest';
export const VIDEO_STATUS_TOPIC = '/cell/video/status';
export const VIDEO_STATUS_TYPE = 'diagnostic_msgs/DiagnosticArray';
/** JPEG quality asked for raw streams (the node rounds it to a step of 10 so viewers share an encoding). */
export const RAW_QUALITY = 70;
/** Widths are asked in steps of this many device pixels: viewers of similar size share one encoding, and a small
 * resize does not ask again. */
export const WIDTH_STEP = 160;
/** A refused or failed request is asked again after this long (while the stream is still shown). */
export const RETRY_MS = 3000;
/** A resize settles this long before the new width is asked for (dragging a window edge asks once). */
export const RESIZE_SETTLE_MS = 250;

/**
 * The width (device pixels) to ask for a frame box `cssWidth` CSS px wide: rounded up to a step of WIDTH_STEP,
 * at least one step.
 * @param {number} cssWidth @param {number} dpr  devicePixelRatio (1 when unknown)
 */
export function wantedWidth(cssWidth, dpr) {
  const k = Number.isFinite(dpr) && dpr > 0 ? dpr : 1;
  const px = Number.isFinite(cssWidth) && cssWidth > 0 ? Math.ceil(cssWidth * k) : 0;
  return Math.max(WIDTH_STEP, Math.ceil(px / WIDTH_STEP) * WIDTH_STEP);
}

/**
 * The /cell/video/request arguments for a raw stream.
 * @param {string} topic @param {number} width @param {number} [quality]
 * @returns {{ topic: string, width: number, quality: number }}
 */
export const videoRequest = (topic, width, quality = RAW_QUALITY) => ({ topic, width: Math.round(width), quality });

/** What a raw stream's viewer asks for at each link level: 0 is what the screen can show, each further level
 * sends fewer bytes a frame (a lower quality first: it costs less to see than a smaller picture). */
export const LINK_LEVELS = Object.freeze([
  { quality: RAW_QUALITY, scale: 1 },
  { quality: 50, scale: 1 },
  { quality: 30, scale: 1 },
  { quality: 30, scale: 0.5 },
  { quality: 30, scale: 0.25 },
]);

/**
 * Follows the link of one raw-stream viewer: when frames come at well under the rate they are sent (the relay's
 * latest-wins lane drops what the link cannot carry), the viewer asks for smaller frames; when they come at the
 * full rate for a while, it tries one level better again, waiting twice as long after each try that failed.
 */
export class LinkAdapter {
  static LOW = 0.7;          // below this share of the expected rate the link is short
  static GOOD = 0.9;         // at or above it the link keeps up
  static DOWN_MS = 4000;     // short this long: one level down
  static UP_MS = 15_000;     // keeping up this long: one level up (doubled after each failed try, up to MAX_UP_MS)
  static MAX_UP_MS = 120_000;
  static SETTLE_MS = 3000;   // after a change, the rate is not judged until the new frames have come this long
  static FAILED_TRY_MS = 10_000;   // down again this soon after going up: the try failed

  constructor() {
    this.level = 0;
    this.upMs = LinkAdapter.UP_MS;
    /** @type {number | null} */ this.lowSince = null;
    /** @type {number | null} */ this.goodSince = null;
    this.settleUntil = 0;
    this.upAt = -Infinity;
  }

  /** What to ask at this level for a frame `width` device px wide. @param {number} width */
  ask(width) {
    const l = LINK_LEVELS[this.level];
    return { width: l.scale === 1 ? width : Math.max(WIDTH_STEP, Math.ceil((width * l.scale) / WIDTH_STEP) * WIDTH_STEP), quality: l.quality };
  }

  /** Back to the best level (another stream, or the page shown again). @param {number} now */
  reset(now) {
    this.level = 0;
    this.upMs = LinkAdapter.UP_MS;
    this.lowSince = this.goodSince = null;
    this.settleUntil = now + LinkAdapter.SETTLE_MS;
  }

  /**
   * Judge the rate frames arrive at. @param {number} now ms @param {number} got frames/s arriving
   * @param {number} expected frames/s sent (the camera's rate, within the subscription's rate cap); 0: not known
   * @returns {boolean} whether the level changed (ask again)
   */
  update(now, got, expected) {
    if (!(expected > 0) || now < this.settleUntil) {
      this.lowSince = this.goodSince = null;
      return false;
    }
    if (got < LinkAdapter.LOW * expected) {
      this.goodSince = null;
      this.lowSince ??= now;
      if (now - this.lowSince < LinkAdapter.DOWN_MS || this.level >= LINK_LEVELS.length - 1) return false;
      if (now - this.upAt < LinkAdapter.FAILED_TRY_MS) this.upMs = Math.min(LinkAdapter.MAX_UP_MS, this.upMs * 2);
      return this.#go(this.level + 1, now);
    }
    this.lowSince = null;
    if (got < LinkAdapter.GOOD * expected) {
      this.goodSince = null;
      return false;
    }
    this.goodSince ??= now;
    if (now - this.goodSince < this.upMs || this.level === 0) return false;
    this.upAt = now;
    return this.#go(this.level - 1, now);
  }

  /** @param {number} level @param {number} now */
  #go(level, now) {
    this.level = level;
    this.lowSince = this.goodSince = null;
    this.settleUntil = now + LinkAdapter.SETTLE_MS;
    return true;
  }
}

/**
 * The camera's own frame rate per /cell/video/status (its "fps" value for the stream `topic`), 0 when not known.
 * @param {any} msg @param {string | null | undefined} topic
 */
export function sourceFps(msg, topic) {
  if (!topic || !Array.isArray(msg?.status)) return 0;
  const st = msg.status.find((/** @type {any} */ s) => s?.hardware_id === topic);
  const v = Array.isArray(st?.values) ? st.values.find((/** @type {any} */ kv) => kv?.key === 'fps') : null;
  const fps = Number(v?.value);
  return Number.isFinite(fps) && fps > 0 ? fps : 0;
}

/**
 * What a /cell/video/request answer gives: the CompressedImage topic to subscribe and its frames' size, or why not.
 * @param {any} res
 * @returns {{ ok: true, topic: string, width: number, height: number } | { ok: false, message: string }}
 */
export function videoAnswer(res) {
  if (res?.ok && typeof res.topic === 'string' && res.topic) {
    return { ok: true, topic: res.topic, width: Number(res.width) || 0, height: Number(res.height) || 0 };
  }
  const message = typeof res?.message === 'string' && res.message ? res.message : m.shell_camera_no_stream();
  return { ok: false, message };
}

/**
 * The level of a diagnostic_msgs/DiagnosticStatus (a byte: a number in JSON, a one-character string from some
 * encoders). @param {unknown} level
 */
function diagLevel(level) {
  if (typeof level === 'number') return level;
  if (typeof level === 'string' && level.length === 1) return level.charCodeAt(0);
  return Number(level) || 0;
}

/**
 * What is wrong with the stream `topic` per /cell/video/status (a DiagnosticArray, one status per raw stream,
 * hardware_id its topic): the message of a WARN (1) or ERROR (2) status, null when fine or not reported.
 * @param {any} msg @param {string | null | undefined} topic @returns {string | null}
 */
export function streamProblem(msg, topic) {
  if (!topic || !Array.isArray(msg?.status)) return null;
  const st = msg.status.find((/** @type {any} */ s) => s?.hardware_id === topic);
  if (!st || diagLevel(st.level) < 1) return null;
  return typeof st.message === 'string' && st.message ? st.message : diagLevel(st.level) >= 2 ? m.shell_camera_problem_error() : m.shell_camera_problem_warning();
}

// ---- the binary hot path: CBOR bytes -> Blob -> ImageBitmap -> canvas (no base64, no data: URLs) ----

/**
 * The image bytes of a CompressedImage: CBOR delivers uint8[] as a Uint8Array; a list of ints is accepted, and a
 * base64 string (the JSON encoding) is decoded as a fallback for servers without CBOR.
 * @param {unknown} data @returns {Uint8Array | null}
 */
export function frameBytes(data) {
  if (data instanceof Uint8Array) return data.length ? data : null;
  if (typeof data === 'string') {
    if (!data) return null;
    try {
      const bin = atob(data);
      const out = new Uint8Array(bin.length);
      for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
      return out;
    } catch {
      return null;
    }
  }
  if (Array.isArray(data) && data.length) return Uint8Array.from(data);
  if (ArrayBuffer.isView(data) && data.byteLength) return new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
  return null;
}

/**
 * Decodes frames one at a time and draws the newest: a frame that arrives while one is decoding replaces any
 * frame still waiting (a slow phone shows fewer frames, never older ones).
 */
export class LatestFrameDecoder {
  /**
   * @param {(bitmap: any) => void} draw  gets each decoded frame (it must close() it when done)
   * @param {(blob: Blob) => Promise<any>} [decode]  createImageBitmap by default
   */
  constructor(draw, decode = (blob) => createImageBitmap(blob)) {
    this.draw = draw;
    this.decode = decode;
    /** @type {Blob | null} */
    this.waiting = null;
    this.busy = false;
    this.closed = false;
    this.decoded = 0;
    this.dropped = 0;
    this.failed = 0;
  }

  /** @param {Uint8Array} bytes @param {string} mime */
  push(bytes, mime) {
    if (this.closed) return;
    if (this.waiting) this.dropped++;
    this.waiting = new Blob([/** @type {BlobPart} */ (bytes)], { type: mime });
    if (!this.busy) this.#next();
  }

  close() {
    this.closed = true;
    this.waiting = null;
  }

  async #next() {
    while (this.waiting && !this.closed) {
      const blob = this.waiting;
      this.waiting = null;
      this.busy = true;
      try {
        const bmp = await this.decode(blob);
        if (this.closed) bmp?.close?.();
        else {
          this.decoded++;
          this.draw(bmp);
        }
      } catch {
        this.failed++;
      } finally {
        this.busy = false;
      }
    }
  }
}

/** Arrival times of the last frames: the stream's frame rate. */
export class FrameStats {
  /** @param {number} [spanMs]  the rate is counted over this much of the recent past */
  constructor(spanMs = 2000) {
    this.spanMs = spanMs;
    /** @type {number[]} */
    this.times = [];
  }

  /** @param {number} t  arrival (ms) */
  add(t) {
    this.times.push(t);
    const from = t - this.spanMs;
    let drop = 0;
    while (drop < this.times.length && this.times[drop] < from) drop++;
    if (drop) this.times.splice(0, drop);
  }

  reset() {
    this.times = [];
  }

  /** Frames per second over the span up to `now` (0 when fewer than two frames came in it). @param {number} now */
  fps(now) {
    const ts = this.times.filter((t) => t >= now - this.spanMs);
    if (ts.length < 2) return 0;
    const dt = ts[ts.length - 1] - ts[0];
    return dt > 0 ? ((ts.length - 1) * 1000) / dt : 0;
  }
}

/**
 * A stream is stale when no frame came for three frame periods (at least `minMs`); `fallbackMs` before the rate
 * is known.
 * @param {number} fps @param {number} [minMs] @param {number} [fallbackMs]
 */
export function staleAfterMs(fps, minMs = 1000, fallbackMs = 2000) {
  return fps > 0 ? Math.max(minMs, 3000 / fps) : fallbackMs;
}

/** "0.1 s", "4 s", "3 min", "2 h" (numbers in the user's locale). @param {number} ms */
export function shortAge(ms) {
  if (!Number.isFinite(ms) || ms < 0) return '—';
  if (ms < 1000) return m.shell_camera_age_s({ n: fmtFixed(ms / 1000, 1) });
  if (ms < 60_000) return m.shell_camera_age_s({ n: fmtNumber(Math.floor(ms / 1000)) });
  if (ms < 3_600_000) return m.shell_camera_age_min({ n: fmtNumber(Math.floor(ms / 60_000)) });
  return m.shell_camera_age_h({ n: fmtNumber(Math.floor(ms / 3_600_000)) });
}

/**
 * What the camera's status line says.
 * @param {{ at: number | null, now: number, fps: number, visible: boolean, name: string, staleMs?: number }} o
 * @returns {{ state: 'live' | 'stale' | 'waiting' | 'hidden', tone: string, label: string, detail: string }}
 */
export function frameStatus({ at, now, fps, visible, name, staleMs }) {
  if (!visible) return { state: 'hidden', tone: 'neutral', label: m.shell_camera_paused(), detail: m.shell_camera_paused_detail() };
  if (at === null) return { state: 'waiting', tone: 'neutral', label: m.shell_camera_waiting(), detail: m.shell_camera_waiting_for({ name }) };
  const age = Math.max(0, now - at);
  if (age > (staleMs ?? staleAfterMs(fps))) {
    return { state: 'stale', tone: 'warn', label: m.shell_camera_stale({ age: shortAge(age) }), detail: m.shell_camera_no_frame({ name, age: shortAge(age) }) };
  }
  return { state: 'live', tone: 'ok', label: m.shell_camera_live(), detail: m.shell_camera_live_detail({ fps: fps > 0 ? fmtFixed(fps, 1) : '—', age: shortAge(age) }) };
}

// ---- zoom and pan: a scale and an offset (CSS px) of the picture inside its box ----

export const ZOOM_MIN = 1;
export const ZOOM_MAX = 8;

/** @typedef {{ scale: number, x: number, y: number }} View  picture point p shows at p * scale + (x, y) */
/** @typedef {{ x: number, y: number, w: number, h: number }} Rect  where the picture sits in its box at 1x */

/** @type {View} */
export const IDENTITY = Object.freeze({ scale: 1, x: 0, y: 0 });

/**
 * Where a picture of iw x ih sits in a w x h box with object-fit: contain (letterboxed, centred).
 * @param {number} iw @param {number} ih @param {number} w @param {number} h @returns {Rect}
 */
export function containRect(iw, ih, w, h) {
  if (!(iw > 0 && ih > 0 && w > 0 && h > 0)) return { x: 0, y: 0, w, h };
  const k = Math.min(w / iw, h / ih);
  const pw = iw * k, ph = ih * k;
  return { x: (w - pw) / 2, y: (h - ph) / 2, w: pw, h: ph };
}

/**
 * Keep the scale in [ZOOM_MIN, ZOOM_MAX] and the picture covering its w x h box where it is larger than the box
 * (no empty border when zoomed), centred where it is smaller.
 * @param {View} v @param {number} w @param {number} h @param {Rect} [pic]  the picture in the box (default: all of it)
 * @returns {View}
 */
export function clampView(v, w, h, pic = { x: 0, y: 0, w, h }) {
  const scale = Math.min(ZOOM_MAX, Math.max(ZOOM_MIN, Number.isFinite(v.scale) ? v.scale : 1));
  /** @param {number} t @param {number} size @param {number} p0 @param {number} plen */
  const clamp = (t, size, p0, plen) => {
    const len = plen * scale;
    if (len <= size) return (size - len) / 2 - p0 * scale;
    const lo = size - (p0 + plen) * scale, hi = -p0 * scale;
    return Math.min(hi, Math.max(lo, Number.isFinite(t) ? t : 0));
  };
  const r = { scale, x: clamp(v.x, w, pic.x, pic.w), y: clamp(v.y, h, pic.y, pic.h) };
  // -0 reads as 0 everywhere but in toEqual.
  return { scale: r.scale, x: r.x + 0, y: r.y + 0 };
}

/**
 * Zoom by `factor` keeping the picture point under (px, py) where it is (wheel, buttons: the box's centre).
 * @param {View} v @param {number} factor @param {number} px @param {number} py @param {number} w @param {number} h @param {Rect} [pic]
 */
export function zoomAt(v, factor, px, py, w, h, pic) {
  const scale = Math.min(ZOOM_MAX, Math.max(ZOOM_MIN, v.scale * factor));
  const k = scale / v.scale;
  return clampView({ scale, x: px - (px - v.x) * k, y: py - (py - v.y) * k }, w, h, pic);
}

/** @param {View} v @param {number} dx @param {number} dy @param {number} w @param {number} h @param {Rect} [pic] */
export function panView(v, dx, dy, w, h, pic) {
  return clampView({ scale: v.scale, x: v.x + dx, y: v.y + dy }, w, h, pic);
}

/**
 * Two-finger pinch: from the view at the gesture's start and both pointers then and now, the view that keeps the
 * picture point under the fingers' midpoint under it, scaled by how far the fingers spread.
 * @param {View} start @param {{x: number, y: number}} a0 @param {{x: number, y: number}} b0
 * @param {{x: number, y: number}} a1 @param {{x: number, y: number}} b1 @param {number} w @param {number} h @param {Rect} [pic]
 * @returns {View}
 */
export function pinchView(start, a0, b0, a1, b1, w, h, pic) {
  const d0 = Math.hypot(b0.x - a0.x, b0.y - a0.y);
  const d1 = Math.hypot(b1.x - a1.x, b1.y - a1.y);
  const m0 = { x: (a0.x + b0.x) / 2, y: (a0.y + b0.y) / 2 };
  const m1 = { x: (a1.x + b1.x) / 2, y: (a1.y + b1.y) / 2 };
  const scale = Math.min(ZOOM_MAX, Math.max(ZOOM_MIN, d0 > 0 ? start.scale * (d1 / d0) : start.scale));
  // The picture point under m0 at the start...
  const cx = (m0.x - start.x) / start.scale;
  const cy = (m0.y - start.y) / start.scale;
  // ...is under m1 now.
  return clampView({ scale, x: m1.x - cx * scale, y: m1.y - cy * scale }, w, h, pic);
}
