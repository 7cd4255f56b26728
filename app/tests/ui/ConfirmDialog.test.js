import { describe, it, expect, vi, afterEach } from 'vitest';
import { render, screen, fireEvent, within } from '@testing-library/svelte';
import ConfirmDialog from '../../src/lib/ui/ConfirmDialog.svelte';

/** A button outside the dialog that has the focus when it opens (what opened it). */
function opener() {
  const b = document.createElement('button');
  b.textContent = 'Open';
  document.body.appendChild(b);
  b.focus();
  return b;
}

afterEach(() => {
  document.body.innerHTML = '';
  vi.restoreAllMocks();
});

const props = (/** @type {Record<string, any>} */ more = {}) => ({
  open: false,
  title: 'Replace parts.csv with parts_v2.csv?',
  message: 'The current parts.csv is kept as a backup.',
  confirmLabel: 'Yes, replace',
  onconfirm: vi.fn(),
  oncancel: vi.fn(),
  ...more,
});

describe('ConfirmDialog (the one confirmation of the app)', () => {
  it('closed: nothing to see; open: a dialog named by its title, described by its message, the action focused', async () => {
    const p = props();
    const { rerender } = render(ConfirmDialog, p);
    expect(screen.queryByRole('dialog')).toBeNull();
    const back = opener();
    await rerender({ ...p, open: true });
    const dialog = screen.getByRole('dialog', { name: 'Replace parts.csv with parts_v2.csv?' });
    const desc = document.getElementById(/** @type {string} */ (dialog.getAttribute('aria-describedby')));
    expect(desc?.textContent).toBe('The current parts.csv is kept as a backup.');
    const yes = within(dialog).getByRole('button', { name: 'Yes, replace' });
    expect(document.activeElement).toBe(yes);
    expect(yes.className).toContain('btn-primary');
    await fireEvent.click(yes);
    expect(p.onconfirm).toHaveBeenCalledTimes(1);
    expect(p.oncancel).not.toHaveBeenCalled();
    // The page closes it: the focus goes back to what opened it.
    await rerender({ ...p, open: false });
    expect(screen.queryByRole('dialog')).toBeNull();
    expect(document.activeElement).toBe(back);
  });

  it('Cancel and Escape (the dialog\'s cancel event) cancel; the browser is kept from closing it by itself', async () => {
    const p = props({ open: true, danger: true, cancelLabel: 'Keep it' });
    render(ConfirmDialog, p);
    const dialog = screen.getByRole('dialog', { name: p.title });
    expect(within(dialog).getByRole('button', { name: 'Yes, replace' }).className).toContain('btn-danger');
    // A dangerous action: the focus is on Cancel, so an Enter does not confirm it.
    expect(document.activeElement).toBe(within(dialog).getByRole('button', { name: 'Keep it' }));
    await fireEvent.click(within(dialog).getByRole('button', { name: 'Keep it' }));
    expect(p.oncancel).toHaveBeenCalledTimes(1);
    const esc = new Event('cancel', { cancelable: true });
    await fireEvent(dialog, esc);
    expect(esc.defaultPrevented).toBe(true);
    expect(p.oncancel).toHaveBeenCalledTimes(2);
    expect(p.onconfirm).not.toHaveBeenCalled();
  });

  it('without a message: no description', () => {
    render(ConfirmDialog, props({ open: true, message: undefined }));
    expect(screen.getByRole('dialog', { name: 'Replace parts.csv with parts_v2.csv?' }).hasAttribute('aria-describedby')).toBe(false);
  });

  it('with the native modal: showModal when opened; a close the page did not ask for is a cancel, its own close is not', async () => {
    const proto = /** @type {any} */ (HTMLDialogElement.prototype);
    const showModal = vi.fn(/** @this {HTMLDialogElement} */ function () {
      this.setAttribute('open', '');
    });
    const close = vi.fn(/** @this {HTMLDialogElement} */ function () {
      this.removeAttribute('open');
      this.dispatchEvent(new Event('close'));
    });
    proto.showModal = showModal;
    proto.close = close;
    try {
      const p = props();
      const { rerender } = render(ConfirmDialog, p);
      await rerender({ ...p, open: true });
      expect(showModal).toHaveBeenCalledTimes(1);
      const dialog = /** @type {HTMLDialogElement} */ (screen.getByRole('dialog'));
      // The browser closes it by itself (a repeated close request): the page hears a cancel.
      dialog.removeAttribute('open');
      await fireEvent(dialog, new Event('close'));
      expect(p.oncancel).toHaveBeenCalledTimes(1);
      await rerender({ ...p, open: false });
      // Opened again, then closed by the page: no cancel.
      await rerender({ ...p, open: true });
      expect(showModal).toHaveBeenCalledTimes(2);
      await rerender({ ...p, open: false });
      expect(close).toHaveBeenCalledTimes(1);
      expect(p.oncancel).toHaveBeenCalledTimes(1);
    } finally {
      delete proto.showModal;
      delete proto.close;
    }
  });
});
