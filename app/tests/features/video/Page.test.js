import { describe, it, expect, vi, beforeEach } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import VideoPage from '../../../src/lib/features/video/Page.svelte';
import { ros } from '../../../src/lib/core/connection.svelte.js';

const feature = { id: 'video', path: '/video', title: 'Cameras', icon: '', load: async () => ({ default: VideoPage }) };
const section = {
  streams: [
    { name: 'Workbench', topic: '/cell/camera/workbench/image/compressed' },
    { name: 'Global view', topic: '/cell/camera/global/image/compressed' },
  ],
};

/** @type {Map<string, any>} */
let live;
beforeEach(() => {
  localStorage.clear();
  live = new Map();
  vi.spyOn(ros, 'subscribe').mockImplementation((topic, _type, _cb, options) => {
    live.set(topic, options);
    return () => live.delete(topic);
  });
});

describe('Cameras page', () => {
  it('lists the streams as segmented buttons; only the shown one is subscribed (CBOR, ~30 fps); the choice is remembered', async () => {
    const { unmount } = render(VideoPage, { feature, section });
    expect(screen.getByRole('radiogroup', { name: 'Camera' })).toBeTruthy();
    expect([...live.keys()]).toEqual([section.streams[0].topic]);
    expect(live.get(section.streams[0].topic)).toMatchObject({ compression: 'cbor', throttle_rate: 33, queue_length: 1 });
    await fireEvent.click(screen.getByRole('radio', { name: 'Global view' }));
    expect([...live.keys()]).toEqual([section.streams[1].topic]);
    expect(screen.getByRole('button', { name: 'Full screen' })).toBeTruthy();
    unmount();
    expect(live.size).toBe(0);
    render(VideoPage, { feature, section });
    expect([...live.keys()]).toEqual([section.streams[1].topic]);
  });
});
