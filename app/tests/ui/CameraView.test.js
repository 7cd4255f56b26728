import { describe, it, expect, vi, afterEach, beforeEach } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import CameraView from '../../src/lib/ui/CameraView.svelte';
import {
  imageSrc, imageMime, bytesToBase64, cameraStreams, frameBytes, LatestFrameDecoder, FrameStats, staleAfterMs, shortAge,
  frameStatus, clampView, zoomAt, panView, pinchView, containRect, IDENTITY, ZOOM_MAX, wantedWidth, videoRequest,
  videoAnswer, streamProblem, RAW_QUALITY, RETRY_MS, LinkAdapter, LINK_LEVELS, sourceFps,
} from '../../src/lib/ui/camera.js';
import { NotConnectedError } from '../../src/lib/core/connection.svelte.js';

const streams = [
  { name: 'Workbench', topic: '/cell/camera/workbench/image/compressed' },
  { name: 'Global view', topic: '/cell/camera/global/image/compressed' },
];
const JPEG = new Uint8Array([0xff, 0xd8, 0xff, 0xe0, 1, 2, 3]);

/** A subscribe() double: which topics are subscribed now (with their options), and a way to deliver to them. */
function fakeSubscribe() {
  /** @type {Map<string, (m: any) => void>} */
  const live = new Map();
  /** @type {Map<string, any>} */
  const options = new Map();
  const subscribe = vi.fn((/** @type {string} */ topic, /** @type {string} */ _type, /** @type {(m: any) => void} */ cb, /** @type {any} */ o) => {
    live.set(topic, cb);
    options.set(topic, o);
    return () => live.delete(topic);
  });
  return { live, options, subscribe };
}

/** A createImageBitmap double: resolves a fake bitmap per blob (and remembers the blobs). */
function fakeDecode() {
  /** @type {Blob[]} */
  const blobs = [];
  const decode = vi.fn(async (/** @type {Blob} */ b) => {
    blobs.push(b);
    return { width: 640, height: 480, close: vi.fn() };
  });
  return { blobs, decode };
}

/** @param {DocumentVisibilityState} v */
function setVisibility(v) {
  Object.defineProperty(document, 'visibilityState', { value: v, configurable: true });
  document.dispatchEvent(new Event('visibilitychange'));
}

const drawImage = vi.fn();
beforeEach(() => {
  drawImage.mockReset();
  vi.spyOn(HTMLCanvasElement.prototype, 'getContext').mockImplementation(() => /** @type {any} */ ({ drawImage }));
});
afterEach(() => {
  vi.useRealTimers();
  // @ts-ignore back to jsdom's own getter
  delete document.visibilityState;
});

describe('camera.js', () => {
  it('makes a data: URL from CompressedImage (base64 string or bytes), with the right type', () => {
    expect(imageSrc({ format: 'jpeg', data: 'AAEC' })).toBe('data:image/jpeg;base64,AAEC');
    expect(imageSrc({ format: 'rgb8; png compressed bgr8', data: [0, 1, 2] })).toBe('data:image/png;base64,AAEC');
    expect(imageSrc({ format: 'jpeg', data: new Uint8Array([0, 1, 2]) })).toBe('data:image/jpeg;base64,AAEC');
    expect(imageSrc({ format: 'jpeg', data: '' })).toBeNull();
    expect(imageSrc(null)).toBeNull();
    expect(imageMime(undefined)).toBe('image/jpeg');
    expect(bytesToBase64(new Uint8Array(70000).fill(65)).length).toBe(Math.ceil(70000 / 3) * 4);
  });

  it('keeps only streams with a topic', () => {
    expect(cameraStreams([{ name: 'A', topic: '/a' }, { topic: '/b' }, { name: 'C' }, null])).toEqual([
      { name: 'A', topic: '/a', type: 'compressed' },
      { name: '/b', topic: '/b', type: 'compressed' },
    ]);
    expect(cameraStreams(undefined)).toEqual([]);
  });

  it('keeps a stream\'s type: raw, or compressed for anything else', () => {
    const got = cameraStreams([{ topic: '/r', type: 'raw' }, { topic: '/c', type: 'compressed' }, { topic: '/x', type: 'h264' }, { topic: '/n' }]);
    expect(got.map((s) => s.type)).toEqual(['raw', 'compressed', 'compressed', 'compressed']);
  });

  it('wanted width: device pixels rounded up to a step of 160, at least 160', () => {
    expect(wantedWidth(390, 3)).toBe(1280); // 1170 device px
    expect(wantedWidth(800, 1)).toBe(800);
    expect(wantedWidth(801, 1)).toBe(960);
    expect(wantedWidth(390, 2)).toBe(800); // 780
    expect(wantedWidth(395, 2)).toBe(800); // a small resize asks the same
    expect(wantedWidth(333.3, 1.5)).toBe(640); // ceil(499.95) = 500
    expect(wantedWidth(1920, 1)).toBe(1920);
    expect(wantedWidth(10, 1)).toBe(160);
    expect(wantedWidth(0, 2)).toBe(160);
    expect(wantedWidth(NaN, 1)).toBe(160);
    expect(wantedWidth(500, 0)).toBe(640); // no ratio known: 1
    expect(wantedWidth(500, NaN)).toBe(640);
  });

  it('video request and answer', () => {
    expect(RAW_QUALITY).toBe(70);
    expect(videoRequest('/cam/image_raw', 800)).toEqual({ topic: '/cam/image_raw', width: 800, quality: 70 });
    expect(videoAnswer({ ok: true, message: '', topic: '/cell/video/cam/w800_q70', width: 800, height: 600, quality: 70 }))
      .toEqual({ ok: true, topic: '/cell/video/cam/w800_q70', width: 800, height: 600 });
    expect(videoAnswer({ ok: false, message: '/x is not a raw camera stream of the cell file', topic: '' }))
      .toEqual({ ok: false, message: '/x is not a raw camera stream of the cell file' });
    expect(videoAnswer({ ok: true, topic: '' })).toMatchObject({ ok: false });
    expect(videoAnswer(undefined)).toMatchObject({ ok: false, message: expect.any(String) });
  });

  it('link adapter: short of the rate for 4 s asks one level smaller (quality first, then width); keeping up 15 s tries one better', () => {
    const a = new LinkAdapter();
    expect(a.ask(1280)).toEqual({ width: 1280, quality: RAW_QUALITY });
    let t = 10_000;
    const run = (/** @type {number} */ ms, /** @type {number} */ got, expected = 30) => {
      let changed = 0;
      for (const end = t + ms; t < end; t += 250) if (a.update(t, got, expected)) changed++;
      return changed;
    };
    expect(run(3750, 12)).toBe(0);           // 40 % of the rate, not yet 4 s
    expect(run(500, 12)).toBe(1);
    expect(a.level).toBe(1);
    expect(a.ask(1280)).toEqual({ width: 1280, quality: 50 });
    expect(run(2750, 5)).toBe(0);            // settling: the new frames are not judged yet
    expect(run(11_500, 12)).toBe(2);
    expect(a.ask(1280)).toEqual({ width: 640, quality: 30 });    // level 3: half the width
    expect(a.ask(1170).width % 160).toBe(0);
    run(60_000, 10);                         // short for ever: the last level, no further
    expect(a.level).toBe(LINK_LEVELS.length - 1);
    expect(a.ask(1280)).toEqual({ width: 320, quality: 30 });
    // between 70 and 90 %: neither down nor up
    const lvl = a.level;
    expect(run(30_000, 24)).toBe(0);
    expect(a.level).toBe(lvl);
    expect(run(14_750, 29.5)).toBe(0);        // keeping up: 15 s before a try
    expect(run(500, 29.5)).toBe(1);
    expect(a.level).toBe(lvl - 1);
    // the try fails within 10 s: back down, and the next try waits twice as long
    expect(run(7500, 12)).toBe(1);
    expect(a.level).toBe(lvl);
    expect(run(29_000, 30)).toBe(0);
    expect(run(4000, 30)).toBe(1);        // 30 s of keeping up after the settling
    // not known (no status yet), or a stream with no rate: nothing changes
    const b = new LinkAdapter();
    for (let i = 0; i < 100; i++) expect(b.update(i * 250, 0, 0)).toBe(false);
    b.update(30_000, 1, 30); b.update(34_000, 1, 30);
    expect(b.level).toBe(1);
    b.reset(40_000);
    expect(b.level).toBe(0);
  });

  it('source fps: the "fps" value of the stream\'s status, 0 when not reported', () => {
    const msg = { status: [
      { hardware_id: '/a', values: [{ key: 'topic', value: '/a' }, { key: 'fps', value: '29.5' }] },
      { hardware_id: '/b', values: [{ key: 'fps', value: 'n/a' }] },
    ] };
    expect(sourceFps(msg, '/a')).toBe(29.5);
    expect(sourceFps(msg, '/b')).toBe(0);
    expect(sourceFps(msg, '/c')).toBe(0);
    expect(sourceFps(null, '/a')).toBe(0);
  });

  it('stream problem: the message of a WARN or ERROR status whose hardware_id is the stream', () => {
    const msg = {
      status: [
        { level: 0, name: 'video: A', message: '640x480 at 15.0 fps', hardware_id: '/a' },
        { level: 2, name: 'video: B', message: 'unsupported encoding yuv422 (shown: rgb8, bgr8, mono8, mono16, 16UC1)', hardware_id: '/b' },
        { level: 1, name: 'video: C', message: 'no frame from /c for 5 s', hardware_id: '/c' },
        { level: '\u0002', message: 'frame size does not match its header', hardware_id: '/d' },
      ],
    };
    expect(streamProblem(msg, '/a')).toBeNull();
    expect(streamProblem(msg, '/b')).toBe('unsupported encoding yuv422 (shown: rgb8, bgr8, mono8, mono16, 16UC1)');
    expect(streamProblem(msg, '/c')).toBe('no frame from /c for 5 s');
    expect(streamProblem(msg, '/d')).toBe('frame size does not match its header');
    expect(streamProblem(msg, '/e')).toBeNull();
    expect(streamProblem(null, '/b')).toBeNull();
  });

  it('frame bytes: CBOR bytes as they are (no copy), ints and base64 as a fallback', () => {
    expect(frameBytes(JPEG)).toBe(JPEG);
    expect([...(frameBytes('AAEC') ?? [])]).toEqual([0, 1, 2]);
    expect([...(frameBytes([5, 6]) ?? [])]).toEqual([5, 6]);
    expect(frameBytes('')).toBeNull();
    expect(frameBytes(new Uint8Array(0))).toBeNull();
    expect(frameBytes(undefined)).toBeNull();
  });

  it('decodes one frame at a time and draws only the newest of those that came meanwhile', async () => {
    /** @type {((v: any) => void)[]} */
    const pending = [];
    const decode = vi.fn((/** @type {Blob} */ b) => new Promise((res) => pending.push(() => res({ id: b.size, close() {} }))));
    const drawn = /** @type {any[]} */ ([]);
    const d = new LatestFrameDecoder((bmp) => drawn.push(bmp.id), decode);
    d.push(new Uint8Array(1), 'image/jpeg');
    d.push(new Uint8Array(2), 'image/jpeg');
    d.push(new Uint8Array(3), 'image/jpeg');
    expect(decode).toHaveBeenCalledTimes(1);
    pending.shift()?.(undefined);
    await vi.waitFor(() => expect(decode).toHaveBeenCalledTimes(2));
    pending.shift()?.(undefined);
    await vi.waitFor(() => expect(drawn).toEqual([1, 3]));
    expect(d.dropped).toBe(1);
    expect(decode.mock.calls[1][0].type).toBe('image/jpeg');
  });

  it('frame rate over the last two seconds; stale after three frame periods; short ages', () => {
    const s = new FrameStats();
    for (let t = 0; t <= 1000; t += 1000 / 15) s.add(t);
    expect(s.fps(1000)).toBeCloseTo(15, 0);
    expect(s.fps(5000)).toBe(0);
    expect(staleAfterMs(15)).toBe(1000);
    expect(staleAfterMs(1)).toBe(3000);
    expect(staleAfterMs(0)).toBe(2000);
    expect(shortAge(120)).toBe('0.1 s');
    expect(shortAge(4200)).toBe('4 s');
    expect(shortAge(95_000)).toBe('1 min');
  });

  it('status: live with rate and age, "Stale: 4 s" when frames stop, waiting, hidden', () => {
    const base = { name: 'Workbench', visible: true, fps: 15 };
    expect(frameStatus({ ...base, at: 1000, now: 1100 })).toMatchObject({ state: 'live', label: 'Live', detail: '15.0 fps · frame 0.1 s old' });
    expect(frameStatus({ ...base, at: 1000, now: 5200 })).toMatchObject({ state: 'stale', tone: 'warn', label: 'Stale: 4 s' });
    expect(frameStatus({ ...base, at: null, now: 0 })).toMatchObject({ state: 'waiting', detail: 'Waiting for Workbench…' });
    expect(frameStatus({ ...base, at: 1000, now: 1100, visible: false }).state).toBe('hidden');
  });

  it('zoom and pan keep the picture covering its box; a pinch keeps the point under the fingers', () => {
    const W = 400, H = 300;
    expect(clampView({ scale: 0.5, x: 10, y: 10 }, W, H)).toEqual(IDENTITY);
    expect(clampView({ scale: 20, x: 0, y: 0 }, W, H).scale).toBe(ZOOM_MAX);
    // Zoom 2x at the centre: the centre stays put.
    const z = zoomAt(IDENTITY, 2, 200, 150, W, H);
    expect(z).toEqual({ scale: 2, x: -200, y: -150 });
    // Pan cannot pull the picture's edge into the box.
    expect(panView(z, 1000, 0, W, H)).toEqual({ scale: 2, x: 0, y: -150 });
    expect(panView(z, -1000, -1000, W, H)).toEqual({ scale: 2, x: -400, y: -300 });
    // Fingers 100 px apart spread to 200 px around (100, 100): 2x, the picture point at (100, 100) stays there.
    const p = pinchView(IDENTITY, { x: 50, y: 100 }, { x: 150, y: 100 }, { x: 0, y: 100 }, { x: 200, y: 100 }, W, H);
    expect(p.scale).toBeCloseTo(2);
    expect(100 * p.scale + p.x).toBeCloseTo(100);
    expect(100 * p.scale + p.y).toBeCloseTo(100);
    // A letterboxed picture (4:3 in a tall box) stays centred while it is narrower than the box, and covers
    // the box (no letterbox band) where it is larger.
    const pic = containRect(640, 480, 390, 700); // 390 x 292.5 at y 203.75
    expect(pic).toEqual({ x: 0, y: 203.75, w: 390, h: 292.5 });
    const z2 = zoomAt(IDENTITY, 2, 195, 350, 390, 700, pic);
    expect(z2.y).toBeCloseTo((700 - 585) / 2 - 203.75 * 2);
    const z4 = clampView({ scale: 4, x: 0, y: 0 }, 390, 700, pic);
    expect(z4.y).toBeCloseTo(-203.75 * 4); // the picture's top edge at the box's top
    expect(clampView({ scale: 4, x: 0, y: -1e6 }, 390, 700, pic).y).toBeCloseTo(700 - (203.75 + 292.5) * 4);
    // Pinching in past 1x goes back to the whole picture.
    expect(pinchView(p, { x: 0, y: 0 }, { x: 300, y: 0 }, { x: 0, y: 0 }, { x: 10, y: 0 }, W, H)).toEqual(IDENTITY);
  });
});

describe('CameraView', () => {
  it('subscribes only the chosen stream, in CBOR with the newest frame only; draws frames on a canvas; switches cleanly', async () => {
    const s = fakeSubscribe();
    const d = fakeDecode();
    render(CameraView, { streams, subscribe: s.subscribe, decode: d.decode });
    expect([...s.live.keys()]).toEqual([streams[0].topic]);
    expect(s.subscribe.mock.calls[0][1]).toBe('sensor_msgs/CompressedImage');
    expect(s.options.get(streams[0].topic)).toMatchObject({ compression: 'cbor', queue_length: 1 });
    expect(screen.queryByRole('img')).toBeNull();
    s.live.get(streams[0].topic)?.({ format: 'jpeg', data: JPEG });
    await vi.waitFor(() => expect(drawImage).toHaveBeenCalledTimes(1));
    flushSync();
    expect(d.blobs[0].type).toBe('image/jpeg');
    expect(d.blobs[0].size).toBe(JPEG.length);
    expect(screen.getByRole('img', { name: 'Workbench camera image' })).toBeTruthy();
    const canvas = /** @type {HTMLCanvasElement} */ (screen.getByTestId('camera-image').querySelector('canvas'));
    expect([canvas.width, canvas.height]).toEqual([640, 480]);

    await fireEvent.change(screen.getByRole('combobox', { name: 'Camera' }), { target: { value: streams[1].topic } });
    expect([...s.live.keys()]).toEqual([streams[1].topic]);
    // The old camera's picture is not shown as the new one's.
    expect(screen.queryByRole('img')).toBeNull();
    expect(screen.getByText(/Waiting for Global view/)).toBeTruthy();
  });

  it('segmented buttons: a radio per stream moves the one subscription', async () => {
    const s = fakeSubscribe();
    render(CameraView, { streams, subscribe: s.subscribe, chooser: 'buttons', decode: fakeDecode().decode });
    const global = screen.getByRole('radio', { name: 'Global view' });
    await fireEvent.click(global);
    expect([...s.live.keys()]).toEqual([streams[1].topic]);
    expect(/** @type {HTMLInputElement} */ (global).checked).toBe(true);
  });

  it('shows the rate and the age, and "Stale: 4 s" when the frames stop', async () => {
    vi.useFakeTimers({ toFake: ['Date', 'setInterval', 'clearInterval'] });
    vi.setSystemTime(100_000);
    const s = fakeSubscribe();
    render(CameraView, { streams, subscribe: s.subscribe, decode: fakeDecode().decode });
    const cb = s.live.get(streams[0].topic);
    for (let i = 0; i < 16; i++) {
      cb?.({ format: 'jpeg', data: JPEG });
      vi.setSystemTime(100_000 + (i + 1) * 66);
    }
    vi.advanceTimersByTime(250);
    flushSync();
    expect(screen.getByTestId('camera-badge').textContent).toBe('Live');
    expect(screen.getByTestId('camera-detail').textContent).toMatch(/^1\d\.\d fps · frame 0\.\d s old$/);
    vi.setSystemTime(100_000 + 15 * 66 + 4100);
    vi.advanceTimersByTime(250);
    flushSync();
    expect(screen.getByTestId('camera-status').dataset.state).toBe('stale');
    expect(screen.getByTestId('camera-badge').textContent).toBe('Stale: 4 s');
  });

  it('Full screen asks the Fullscreen API, or shows a fixed overlay where it is missing; Reset zoom after zooming', async () => {
    const s = fakeSubscribe();
    render(CameraView, { streams, subscribe: s.subscribe, decode: fakeDecode().decode });
    const root = screen.getByTestId('camera');
    /** @type {any} */ (root).requestFullscreen = undefined;
    await fireEvent.click(screen.getByRole('button', { name: 'Full screen' }));
    expect(root.classList.contains('expanded')).toBe(true);
    const exit = screen.getByRole('button', { name: 'Exit full screen' });
    expect(exit.getAttribute('aria-pressed')).toBe('true');
    await fireEvent.keyDown(document, { key: 'Escape' });
    expect(root.classList.contains('expanded')).toBe(false);

    const req = vi.fn(async () => {});
    /** @type {any} */ (root).requestFullscreen = req;
    await fireEvent.click(screen.getByRole('button', { name: 'Full screen' }));
    expect(req).toHaveBeenCalled();

    const reset = screen.getByRole('button', { name: 'Reset zoom' });
    expect(/** @type {HTMLButtonElement} */ (reset).disabled).toBe(true);
    await fireEvent.click(screen.getByRole('button', { name: 'Zoom in' }));
    expect(screen.getByTestId('camera-zoom').textContent).toMatch(/Zoom 1\.5×/);
    expect(/** @type {HTMLButtonElement} */ (reset).disabled).toBe(false);
    await fireEvent.click(reset);
    expect(screen.queryByTestId('camera-zoom')).toBeNull();
  });

  it('unsubscribes while the page is hidden and when it goes away', () => {
    const s = fakeSubscribe();
    const { unmount } = render(CameraView, { streams, subscribe: s.subscribe });
    setVisibility('hidden');
    flushSync();
    expect(s.live.size).toBe(0);
    setVisibility('visible');
    flushSync();
    expect(s.live.size).toBe(1);
    unmount();
    expect(s.live.size).toBe(0);
  });

  it('says so when the cell has no cameras', () => {
    const s = fakeSubscribe();
    render(CameraView, { streams: [], subscribe: s.subscribe });
    expect(screen.getByText(/No camera streams/)).toBeTruthy();
    expect(s.subscribe).not.toHaveBeenCalled();
  });
});

describe('CameraView: raw streams (asked of the video service)', () => {
  const RAW = '/cell/camera/arm/image_raw';
  const rawStreams = [
    { name: 'Arm', topic: RAW, type: 'raw' },
    { name: 'Workbench', topic: '/cell/camera/workbench/image/compressed', type: 'compressed' },
  ];
  const OUT = (/** @type {number} */ w) => `/cell/video/cell_camera_arm_image_raw/w${w}_q70`;
  const ok = (/** @type {number} */ w) => ({ ok: true, message: '', topic: OUT(w), width: w, height: (w * 3) / 4, quality: 70 });
  const REQ = ['/cell/video/request', 'cell_msgs/VideoRequest'];

  /** A callService double whose answers the test gives, one call at a time. */
  function fakeService() {
    /** @type {{ name: string, type: string, args: any, resolve: (v: any) => void, reject: (e: any) => void }[]} */
    const calls = [];
    const callService = vi.fn(
      (/** @type {string} */ name, /** @type {string} */ type, /** @type {any} */ args) =>
        new Promise((resolve, reject) => calls.push({ name, type, args, resolve, reject })),
    );
    return { calls, callService };
  }

  /** ResizeObservers made by the component; resize() sets the frame's width and tells them. */
  /** @type {{ cb: () => void, el: Element | null, gone: boolean }[]} */
  let observers = [];
  beforeEach(() => {
    observers = [];
    vi.stubGlobal(
      'ResizeObserver',
      class {
        /** @param {() => void} cb */
        constructor(cb) {
          /** @type {{ cb: () => void, el: Element | null, gone: boolean }} */
          this.o = { cb, el: null, gone: false };
          observers.push(this.o);
        }
        /** @param {Element} el */
        observe(el) {
          this.o.el = el;
        }
        disconnect() {
          this.o.gone = true;
        }
      },
    );
  });
  afterEach(() => vi.unstubAllGlobals());

  /** @param {number} cssWidth */
  function resize(cssWidth) {
    const el = screen.getByTestId('camera-frame');
    Object.defineProperty(el, 'clientWidth', { value: cssWidth, configurable: true });
    for (const o of observers) if (!o.gone && o.el === el) o.cb();
  }

  /** Let answered promises run and the effects they caused. */
  async function settle() {
    for (let i = 0; i < 5; i++) await Promise.resolve();
    flushSync();
  }

  it('asks for a JPEG stream at the frame\'s width and subscribes the topic it names (CBOR, newest frame only)', async () => {
    const s = fakeSubscribe();
    const svc = fakeService();
    const d = fakeDecode();
    render(CameraView, { streams: rawStreams, subscribe: s.subscribe, callService: svc.callService, decode: d.decode });
    const root = screen.getByTestId('camera');
    expect(root.dataset.type).toBe('raw');
    // jsdom lays nothing out (width 0): the smallest step.
    expect(svc.calls.map((c) => [c.name, c.type, c.args])).toEqual([[...REQ, { topic: RAW, width: 160, quality: 70 }]]);
    expect(root.dataset.requestWidth).toBe('160');
    // The raw topic itself is never subscribed; only the status until the answer comes.
    expect([...s.live.keys()]).toEqual(['/cell/video/status']);
    expect(root.dataset.sourceTopic).toBeUndefined();

    svc.calls[0].resolve(ok(160));
    await settle();
    expect([...s.live.keys()].sort()).toEqual([OUT(160), '/cell/video/status'].sort());
    const call = s.subscribe.mock.calls.find((c) => c[0] === OUT(160));
    expect(call?.[1]).toBe('sensor_msgs/CompressedImage');
    expect(s.options.get(OUT(160))).toEqual({ throttle_rate: 100, queue_length: 1, compression: 'cbor' });
    expect(s.options.get('/cell/video/status')).toEqual({ queue_length: 1 });
    expect(s.subscribe.mock.calls.find((c) => c[0] === '/cell/video/status')?.[1]).toBe('diagnostic_msgs/DiagnosticArray');
    expect(root.dataset.sourceTopic).toBe(OUT(160));

    s.live.get(OUT(160))?.({ format: 'jpeg', data: JPEG });
    await vi.waitFor(() => expect(drawImage).toHaveBeenCalledTimes(1));
    flushSync();
    expect(screen.getByRole('img', { name: 'Arm camera image' })).toBeTruthy();
    expect(screen.queryByTestId('camera-error')).toBeNull();
  });

  it('asks again when the frame\'s size settles at another step; the same topic keeps the subscription, another moves it', async () => {
    vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout'] });
    vi.stubGlobal('devicePixelRatio', 2);
    const s = fakeSubscribe();
    const svc = fakeService();
    render(CameraView, { streams: rawStreams, subscribe: s.subscribe, callService: svc.callService, decode: fakeDecode().decode });
    svc.calls[0].resolve(ok(160));
    await settle();
    const root = screen.getByTestId('camera');
    expect(root.dataset.sourceTopic).toBe(OUT(160));

    // A resize is asked about once it settles (~250 ms), not on every step of the drag.
    resize(300);
    vi.advanceTimersByTime(100);
    resize(390);
    vi.advanceTimersByTime(200);
    flushSync();
    expect(svc.calls).toHaveLength(1);
    vi.advanceTimersByTime(60);
    flushSync();
    expect(svc.calls).toHaveLength(2);
    expect(svc.calls[1].args).toEqual({ topic: RAW, width: 800, quality: 70 }); // 390 css px x 2 = 780 -> 800
    expect(root.dataset.requestWidth).toBe('800');
    // Until the answer, the old size keeps showing.
    expect(s.live.has(OUT(160))).toBe(true);

    svc.calls[1].resolve(ok(800));
    await settle();
    expect([...s.live.keys()].sort()).toEqual([OUT(800), '/cell/video/status'].sort());
    expect(root.dataset.sourceTopic).toBe(OUT(800));

    // A small resize stays in the same step: not asked again.
    resize(395);
    vi.advanceTimersByTime(300);
    flushSync();
    expect(svc.calls).toHaveLength(2);

    // Full screen (a larger box): asked again; an answer naming the same topic (the camera is no wider) keeps it.
    const subs = s.subscribe.mock.calls.length;
    resize(1000);
    vi.advanceTimersByTime(300);
    flushSync();
    expect(svc.calls[2].args.width).toBe(2080);
    svc.calls[2].resolve(ok(800));
    await settle();
    expect(s.subscribe.mock.calls.length).toBe(subs);
    expect(s.live.has(OUT(800))).toBe(true);
  });

  it('a refusal or a failed call shows in place and is asked again after 3 s while shown', async () => {
    vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout'] });
    const s = fakeSubscribe();
    const svc = fakeService();
    const { unmount } = render(CameraView, { streams: rawStreams, subscribe: s.subscribe, callService: svc.callService, decode: fakeDecode().decode });
    svc.calls[0].resolve({ ok: false, message: '/cell/camera/arm/image_raw is not a raw camera stream of the cell file', topic: '' });
    await settle();
    const err = screen.getByTestId('camera-error');
    expect(err.getAttribute('role')).toBe('status');
    expect(err.textContent).toBe('Camera error: /cell/camera/arm/image_raw is not a raw camera stream of the cell file');
    expect(screen.getByTestId('camera').dataset.sourceTopic).toBeUndefined();

    vi.advanceTimersByTime(2900);
    expect(svc.calls).toHaveLength(1);
    vi.advanceTimersByTime(100);
    expect(svc.calls).toHaveLength(2);
    svc.calls[1].reject(new NotConnectedError('service call'));
    await settle();
    expect(screen.getByTestId('camera-error').textContent).toMatch(/^Camera error: Not connected to ROS/);
    vi.advanceTimersByTime(3000);
    expect(svc.calls).toHaveLength(3);
    svc.calls[2].resolve(ok(160));
    await settle();
    expect(screen.queryByTestId('camera-error')).toBeNull();
    expect(s.live.has(OUT(160))).toBe(true);

    unmount();
    expect(s.live.size).toBe(0);
    vi.advanceTimersByTime(10_000);
    expect(svc.calls).toHaveLength(3);
  });

  it('no frame for 3 s after an answer (a video node that restarted forgot the output): asked again, the subscription kept', async () => {
    vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout'] });
    const s = fakeSubscribe();
    const svc = fakeService();
    render(CameraView, { streams: rawStreams, subscribe: s.subscribe, callService: svc.callService, decode: fakeDecode().decode });
    svc.calls[0].resolve(ok(160));
    await settle();
    const subscribed = s.subscribe.mock.calls.filter((c) => c[0] === OUT(160)).length;
    vi.advanceTimersByTime(RETRY_MS);
    expect(svc.calls).toHaveLength(2);
    expect(svc.calls[1].args).toEqual({ topic: RAW, width: 160, quality: 70 });
    svc.calls[1].resolve(ok(160));
    await settle();
    expect(s.subscribe.mock.calls.filter((c) => c[0] === OUT(160)).length).toBe(subscribed);
    // Frames flow: nothing more is asked.
    s.live.get(OUT(160))?.({ format: 'jpeg', data: JPEG });
    vi.advanceTimersByTime(RETRY_MS);
    expect(svc.calls).toHaveLength(2);
  });

  it('frames arriving at a third of the camera\'s rate: after some seconds it asks a lower quality and moves to that topic', async () => {
    vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout', 'setInterval', 'clearInterval', 'Date'] });
    const s = fakeSubscribe();
    const svc = fakeService();
    render(CameraView, { streams: rawStreams, subscribe: s.subscribe, callService: svc.callService, decode: fakeDecode().decode, throttleMs: 20 });
    const root = screen.getByTestId('camera');
    svc.calls[0].resolve(ok(160));
    await settle();
    s.live.get('/cell/video/status')?.({ status: [{ level: 0, hardware_id: RAW, message: 'ok', values: [{ key: 'fps', value: '30.0' }] }] });
    expect(root.dataset.linkLevel).toBe('0');
    // 10 frames a second of 30 for 6 s: still at the first level (3 s settling, then 4 s short)
    for (let i = 0; i < 60; i++) {
      s.live.get(OUT(160))?.({ format: 'jpeg', data: JPEG });
      vi.advanceTimersByTime(100);
      flushSync();
    }
    expect(svc.calls.map((c) => c.args.quality)).not.toContain(50);
    for (let i = 0; i < 30 && !svc.calls.some((c) => c.args.quality === 50); i++) {
      s.live.get(OUT(160))?.({ format: 'jpeg', data: JPEG });
      vi.advanceTimersByTime(100);
      flushSync();
    }
    const asked = svc.calls.find((c) => c.args.quality === 50);
    expect(asked?.args).toEqual({ topic: RAW, width: 160, quality: 50 });
    expect(root.dataset.linkLevel).toBe('1');
    expect(screen.getByTestId('camera-link').textContent).toMatch(/slow link/);
    asked?.resolve({ ...ok(160), topic: '/cell/video/cell_camera_arm_image_raw/w160_q50', quality: 50 });
    await settle();
    expect(s.live.has('/cell/video/cell_camera_arm_image_raw/w160_q50')).toBe(true);
    expect(s.live.has(OUT(160))).toBe(false);
    expect(root.dataset.requestQuality).toBe('50');
  });

  it('nothing is asked or subscribed while the page is hidden; back visible, it asks first', async () => {
    vi.useFakeTimers({ toFake: ['setTimeout', 'clearTimeout'] });
    const s = fakeSubscribe();
    const svc = fakeService();
    render(CameraView, { streams: rawStreams, subscribe: s.subscribe, callService: svc.callService, decode: fakeDecode().decode });
    svc.calls[0].resolve({ ok: false, message: 'busy', topic: '' });
    await settle();
    setVisibility('hidden');
    flushSync();
    expect(s.live.size).toBe(0);
    vi.advanceTimersByTime(10_000);
    expect(svc.calls).toHaveLength(1); // the pending retry went with the page

    setVisibility('visible');
    flushSync();
    expect(svc.calls).toHaveLength(2);
    svc.calls[1].resolve(ok(160));
    await settle();
    expect(s.live.has(OUT(160))).toBe(true);

    setVisibility('hidden');
    flushSync();
    expect(s.live.size).toBe(0);
    setVisibility('visible');
    flushSync();
    // Not the old output at once (unwatched, it may be gone): the answer decides.
    expect([...s.live.keys()]).toEqual(['/cell/video/status']);
    expect(svc.calls).toHaveLength(3);
    svc.calls[2].resolve(ok(160));
    await settle();
    expect(s.live.has(OUT(160))).toBe(true);
  });

  it('shows the video node\'s error for the shown stream over the picture; hidden when fine', async () => {
    const s = fakeSubscribe();
    const svc = fakeService();
    render(CameraView, { streams: rawStreams, subscribe: s.subscribe, callService: svc.callService, decode: fakeDecode().decode });
    svc.calls[0].resolve(ok(160));
    await settle();
    const status = s.live.get('/cell/video/status');
    status?.({ status: [{ level: 2, name: 'video: Arm', message: 'unsupported encoding yuv422 (shown: rgb8, bgr8, mono8, mono16, 16UC1)', hardware_id: RAW, values: [] }] });
    flushSync();
    const err = screen.getByTestId('camera-error');
    expect(err.textContent).toBe('Camera error: unsupported encoding yuv422 (shown: rgb8, bgr8, mono8, mono16, 16UC1)');
    // In the frame, over the picture: still subscribed, the picture still shows.
    expect(screen.getByTestId('camera-frame').contains(err)).toBe(true);
    expect(s.live.has(OUT(160))).toBe(true);

    status?.({ status: [{ level: 1, message: 'frame size does not match its header', hardware_id: RAW }] });
    flushSync();
    expect(screen.getByTestId('camera-error').textContent).toBe('Camera error: frame size does not match its header');
    status?.({ status: [{ level: 2, message: 'other camera broken', hardware_id: '/other' }, { level: 0, message: '640x480 at 15.0 fps', hardware_id: RAW }] });
    flushSync();
    expect(screen.queryByTestId('camera-error')).toBeNull();
  });

  it('another stream: the raw stream\'s subscriptions go, a late answer for it is ignored; compressed streams as before', async () => {
    const s = fakeSubscribe();
    const svc = fakeService();
    render(CameraView, { streams: rawStreams, subscribe: s.subscribe, callService: svc.callService, decode: fakeDecode().decode });
    const root = screen.getByTestId('camera');
    await fireEvent.change(screen.getByRole('combobox', { name: 'Camera' }), { target: { value: rawStreams[1].topic } });
    expect([...s.live.keys()]).toEqual([rawStreams[1].topic]);
    expect(root.dataset.type).toBe('compressed');
    expect(root.dataset.requestWidth).toBeUndefined();
    expect(root.dataset.sourceTopic).toBe(rawStreams[1].topic);
    expect(svc.calls).toHaveLength(1);

    // Back to the raw stream before the first answer came: that answer is for a view that is gone.
    await fireEvent.change(screen.getByRole('combobox', { name: 'Camera' }), { target: { value: RAW } });
    expect(svc.calls).toHaveLength(2);
    svc.calls[0].resolve(ok(320));
    await settle();
    expect([...s.live.keys()]).toEqual(['/cell/video/status']);
    svc.calls[1].resolve(ok(160));
    await settle();
    expect([...s.live.keys()].sort()).toEqual([OUT(160), '/cell/video/status'].sort());
  });

  it('without a callService a raw stream says it needs the video service', () => {
    const s = fakeSubscribe();
    render(CameraView, { streams: rawStreams, subscribe: s.subscribe, decode: fakeDecode().decode });
    expect(screen.getByTestId('camera-error').textContent).toBe('Camera error: This camera needs the video service');
    expect(s.live.has(RAW)).toBe(false);
  });
});
