import { describe, it, expect, vi } from 'vitest';
import { themeColor, onThemeChange } from '../../src/lib/core/theme-colors.js';

describe('theme colours for canvases', () => {
  it("reads the drawn theme's custom property, else the fallback", () => {
    const root = document.createElement('div');
    document.body.append(root);
    expect(themeColor('--chart-1', '#dc2626', root)).toBe('#dc2626');
    root.style.setProperty('--chart-1', ' #f87171 ');
    expect(themeColor('--chart-1', '#dc2626', root)).toBe('#f87171');
    root.remove();
  });
  it('calls back when the theme changes, not for other attributes, and stops when asked', async () => {
    const root = document.createElement('div');
    const fn = vi.fn();
    const stop = onThemeChange(fn, root);
    root.dataset.glove = '';
    await Promise.resolve();
    expect(fn).not.toHaveBeenCalled();
    root.dataset.theme = 'dark';
    await vi.waitFor(() => expect(fn).toHaveBeenCalledTimes(1));
    stop();
    root.dataset.theme = 'contrast';
    await new Promise((r) => setTimeout(r, 0));
    expect(fn).toHaveBeenCalledTimes(1);
  });
});
