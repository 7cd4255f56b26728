import { describe, it, expect, vi, afterEach } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import CameraView from '../../src/lib/ui/CameraView.svelte';
import { imageSrc, imageMime, bytesToBase64, cameraStreams } from '../../src/lib/ui/camera.js';

const streams = [
  { name: 'Workbench', topic: '/cell/camera/workbench/image/compressed' },
  { name: 'Global view', topic: '/cell/camera/global/image/compressed' },
];

/** A subscribe() double: which topics are subscribed now, and a way to deliver to them. */
function fakeSubscribe() {
  /** @type {Map<string, (m: any) => void>} */
  const live = new Map();
  const subscribe = vi.fn((/** @type {string} */ topic, /** @type {string} */ _type, /** @type {(m: any) => void} */ cb) => {
    live.set(topic, cb);
    return () => live.delete(topic);
  });
  return { live, subscribe };
}

/** @param {DocumentVisibilityState} v */
function setVisibility(v) {
  Object.defineProperty(document, 'visibilityState', { value: v, configurable: true });
  document.dispatchEvent(new Event('visibilitychange'));
}

afterEach(() => {
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
    expect(cameraStreams([{ name: 'A', topic: '/a' }, { topic: '/b' }, { name: 'C' }, null])).toEqual([{ name: 'A', topic: '/a' }, { name: '/b', topic: '/b' }]);
    expect(cameraStreams(undefined)).toEqual([]);
  });
});

describe('CameraView', () => {
  it('subscribes only the chosen stream, shows its image with its age, and switches cleanly', async () => {
    const s = fakeSubscribe();
    render(CameraView, { streams, subscribe: s.subscribe });
    expect([...s.live.keys()]).toEqual([streams[0].topic]);
    expect(s.subscribe.mock.calls[0][1]).toBe('sensor_msgs/CompressedImage');
    s.live.get(streams[0].topic)?.({ format: 'jpeg', data: 'AAEC' });
    flushSync();
    const img = /** @type {HTMLImageElement} */ (screen.getByRole('img', { name: 'Workbench camera image' }));
    expect(img.getAttribute('src')).toBe('data:image/jpeg;base64,AAEC');
    expect(screen.getByTestId('camera-freshness-age').textContent).toBe('updated just now');

    await fireEvent.change(screen.getByRole('combobox', { name: 'Camera' }), { target: { value: streams[1].topic } });
    expect([...s.live.keys()]).toEqual([streams[1].topic]);
    // The old camera's picture is not shown as the new one's.
    expect(screen.queryByRole('img')).toBeNull();
    expect(screen.getByText(/Waiting for Global view/)).toBeTruthy();
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
