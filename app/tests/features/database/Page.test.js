import { describe, it, expect, vi, beforeEach, afterEach } from 'vitest';
import { render, screen, fireEvent, within } from '@testing-library/svelte';
import { flushSync } from 'svelte';
import DatabasePage from '../../../src/lib/features/database/Page.svelte';
import { session } from '../../../src/lib/core/session.svelte.js';

const feature = { id: 'database', path: '/database', title: 'Database', icon: '', load: async () => ({ default: DatabasePage }) };
const section = { files: ['parts.csv', 'fixtures.yaml'], max_upload_bytes: 1000 };
const files = [
  { name: 'parts.csv', size: 120, mtime: '2026-11-20T10:00:00.000Z', exists: true },
  { name: 'fixtures.yaml', size: null, mtime: null, exists: false },
];
const backup = 'parts.csv.2026-11-21T08:00:00.000Z';

/** @type {{ method: string, url: string, body: any }[]} */
let calls;
/** Answers by "METHOD path" (query included); a function gets the body. @type {Record<string, any>} */
let routes;

const json = (/** @type {any} */ data, status = 200) => new Response(JSON.stringify(data), { status });

beforeEach(() => {
  session.offline = false;
  calls = [];
  routes = {
    'GET /api/database/files': () => json({ max_upload_bytes: 1000, files }),
    'GET /api/database/drives': () => json({ drives: [{ id: '0:usb1', label: 'usb1', path: '/media/usb1' }] }),
    'GET /api/database/drives/0%3Ausb1/files': () => json({ drive: '0:usb1', path: '', entries: [
      { name: 'old', type: 'dir' },
      { name: 'notes.txt', type: 'file', size: 5, mtime: '2026-11-22T09:00:00.000Z', targets: [] },
      { name: 'parts_v2.csv', type: 'file', size: 90, mtime: '2026-11-22T09:00:00.000Z', targets: ['parts.csv'] },
    ] }),
    'GET /api/database/drives/0%3Ausb1/files?path=old': () => json({ drive: '0:usb1', path: 'old', entries: [] }),
    'POST /api/database/files/parts.csv/from-drive': () => json({ file: { ...files[0], size: 90 }, backup: 'parts.csv.2026-11-22T10:00:00.000Z' }),
    'GET /api/database/files/parts.csv/backups': () => json({ backups: [{ name: backup, size: 120, mtime: '2026-11-21T08:00:00.000Z' }] }),
    'POST /api/database/files/parts.csv/restore': () => json({ file: files[0], backup: 'parts.csv.2026-11-22T11:00:00.000Z' }),
  };
  vi.stubGlobal('fetch', vi.fn(async (/** @type {string} */ url, /** @type {RequestInit} */ init) => {
    const method = init?.method ?? 'GET';
    const body = init?.body ? JSON.parse(String(init.body)) : undefined;
    calls.push({ method, url, body });
    const r = routes[`${method} ${url}`];
    return r ? r(body) : json({ error: `no route ${method} ${url}` }, 404);
  }));
});
afterEach(() => vi.unstubAllGlobals());

describe('Database page', () => {
  it('lists the database files with their state, and the drive with its folders and files', async () => {
    render(DatabasePage, { feature, section });
    const parts = await screen.findByText('parts.csv', { selector: '.tname' });
    const item = /** @type {HTMLElement} */ (parts.closest('li'));
    expect(within(item).getByText('Present')).toBeTruthy();
    expect(screen.getByText('Missing')).toBeTruthy();
    expect(await screen.findByRole('button', { name: 'Open folder old' })).toBeTruthy();
    expect(screen.getByRole('radio', { name: 'parts_v2.csv' })).toBeTruthy();
    expect(screen.getByTestId('drive-path').textContent).toBe('/media/usb1');
    await fireEvent.click(screen.getByRole('button', { name: 'Open folder old' }));
    expect(await screen.findByText('This folder is empty.')).toBeTruthy();
    expect(screen.getByTestId('drive-path').textContent).toBe('/media/usb1/old');
    await fireEvent.click(screen.getByRole('button', { name: 'Up one folder' }));
    expect(await screen.findByRole('radio', { name: 'parts_v2.csv' })).toBeTruthy();
  });

  it('replace from a drive: asks "Replace parts.csv with /media/usb1/parts_v2.csv?", sends only on Yes, shows the result', async () => {
    render(DatabasePage, { feature, section });
    await fireEvent.click(await screen.findByRole('radio', { name: 'parts_v2.csv' }));
    const replaceBtn = screen.getByRole('button', { name: 'Replace parts.csv' });
    replaceBtn.focus();
    await fireEvent.click(replaceBtn);
    // The shared modal confirmation: named by its question, described by what becomes of the current file.
    const dialog = screen.getByRole('dialog', { name: 'Replace parts.csv with /media/usb1/parts_v2.csv?' });
    expect(dialog.getAttribute('aria-describedby')).toBeTruthy();
    expect(within(dialog).getByText('The current parts.csv is kept as a backup, which can be restored.')).toBeTruthy();
    expect(document.activeElement).toBe(within(dialog).getByRole('button', { name: 'Yes, replace' }));
    // Cancel: nothing sent, the dialog is gone, the focus is back on Replace.
    await fireEvent.click(within(dialog).getByRole('button', { name: 'Cancel' }));
    expect(screen.queryByRole('dialog')).toBeNull();
    expect(document.activeElement).toBe(replaceBtn);
    expect(calls.some((c) => c.method === 'POST')).toBe(false);
    // Escape (the dialog's cancel event) cancels too.
    await fireEvent.click(replaceBtn);
    await fireEvent(screen.getByRole('dialog', { name: /^Replace parts\.csv with / }), new Event('cancel', { cancelable: true }));
    expect(screen.queryByRole('dialog')).toBeNull();
    expect(document.activeElement).toBe(replaceBtn);
    expect(calls.some((c) => c.method === 'POST')).toBe(false);
    await fireEvent.click(replaceBtn);
    expect(document.activeElement?.textContent).toBe('Yes, replace');
    await fireEvent.click(screen.getByRole('button', { name: 'Yes, replace' }));
    expect(screen.queryByRole('dialog')).toBeNull();
    const done = await screen.findByTestId('replace-done');
    expect(done.textContent).toContain('parts.csv replaced with /media/usb1/parts_v2.csv');
    expect(done.textContent).toContain('parts.csv.2026-11-22T10:00:00.000Z');
    expect(calls.find((c) => c.method === 'POST')).toMatchObject({ url: '/api/database/files/parts.csv/from-drive', body: { drive: '0:usb1', path: 'parts_v2.csv' } });
    // The file list is read again after the change.
    expect(calls.filter((c) => c.url === '/api/database/files').length).toBe(2);
  });

  it("shows the server's error as it came (a wrong extension), with a warning before", async () => {
    routes['POST /api/database/files/parts.csv/from-drive'] = () => json({ error: 'parts.csv needs a .csv file, not .txt' }, 415);
    render(DatabasePage, { feature, section });
    await fireEvent.click(await screen.findByRole('radio', { name: 'notes.txt' }));
    await fireEvent.change(screen.getByRole('combobox', { name: 'Database file to replace' }), { target: { value: 'parts.csv' } });
    expect(screen.getByRole('note').textContent).toContain('parts.csv takes only .csv files');
    await fireEvent.click(screen.getByRole('button', { name: 'Replace parts.csv' }));
    expect(screen.getByRole('dialog', { name: 'Replace parts.csv with /media/usb1/notes.txt?' })).toBeTruthy();
    await fireEvent.click(screen.getByRole('button', { name: 'Yes, replace' }));
    const alert = await screen.findByTestId('replace-failed');
    expect(alert.textContent).toContain('Could not replace parts.csv: parts.csv needs a .csv file, not .txt');
    await fireEvent.click(screen.getByRole('button', { name: 'Dismiss the message about parts.csv' }));
    expect(screen.queryByTestId('replace-failed')).toBeNull();
  });

  it('backups: listed newest first with Restore, confirmed, then the result', async () => {
    render(DatabasePage, { feature, section });
    await fireEvent.click(await screen.findByRole('button', { name: 'Show backups of parts.csv' }));
    const restore = await screen.findByRole('button', { name: `Restore parts.csv from ${backup}` });
    await fireEvent.click(restore);
    const ask = screen.getByRole('dialog', { name: `Restore parts.csv from the backup ${backup}?` });
    expect(ask.textContent).toContain('The current parts.csv is kept as a backup');
    await fireEvent.click(within(ask).getByRole('button', { name: 'Yes, restore' }));
    expect((await screen.findByTestId('restore-done')).textContent).toContain(`parts.csv restored from ${backup}`);
    expect(calls.find((c) => c.url.endsWith('/restore'))?.body).toEqual({ backup });
    expect(screen.getByRole('button', { name: 'Hide backups of parts.csv' }).getAttribute('aria-expanded')).toBe('true');
  });

  it('a file from this device: the picker, then the upload with progress', async () => {
    /** @type {any} */
    let xhr;
    class FakeXHR {
      upload = /** @type {any} */ ({});
      status = 0;
      responseText = '';
      open() {}
      setRequestHeader() {}
      /** @param {FormData} form */
      send(form) {
        xhr = this;
        this.form = form;
      }
    }
    vi.stubGlobal('XMLHttpRequest', FakeXHR);
    render(DatabasePage, { feature, section });
    await screen.findByText('parts.csv', { selector: '.tname' });
    await fireEvent.click(screen.getByRole('radio', { name: 'File on this device' }));
    const input = /** @type {HTMLInputElement} */ (screen.getByLabelText('File from this device'));
    expect(input.accept).toBe('.csv,.yaml');
    const file = new File(['name: jig\n'], 'fixtures_v3.yaml');
    await fireEvent.change(input, { target: { files: [file] } });
    expect(/** @type {HTMLSelectElement} */ (screen.getByRole('combobox', { name: 'Database file to replace' })).value).toBe('fixtures.yaml');
    await fireEvent.click(screen.getByRole('button', { name: 'Replace fixtures.yaml' }));
    const ask = screen.getByRole('dialog', { name: 'Replace fixtures.yaml with fixtures_v3.yaml from this device?' });
    expect(ask.textContent).toContain('There is no fixtures.yaml on the robot PC yet, so there is nothing to back up.');
    await fireEvent.click(screen.getByRole('button', { name: 'Yes, replace' }));
    await vi.waitFor(() => expect(xhr).toBeTruthy());
    xhr.upload.onprogress({ loaded: 5, total: 10, lengthComputable: true });
    const bar = /** @type {HTMLProgressElement} */ (await screen.findByTestId('replace-progress'));
    expect(bar.value).toBe(0.5);
    expect(screen.getByTestId('replace-running').textContent).toContain('50 %');
    xhr.status = 200;
    xhr.responseText = JSON.stringify({ file: { name: 'fixtures.yaml', size: 10, mtime: '', exists: true }, backup: null });
    xhr.onload();
    expect((await screen.findByTestId('replace-done')).textContent).toContain('fixtures.yaml replaced with fixtures_v3.yaml from this device. There was no earlier file to back up.');
  });

  it('403: access denied', async () => {
    routes['GET /api/database/files'] = () => json({ error: 'no' }, 403);
    render(DatabasePage, { feature, section });
    expect(await screen.findByTestId('access-denied')).toBeTruthy();
  });

  it('offline: nothing can be sent', async () => {
    render(DatabasePage, { feature, section });
    await fireEvent.click(await screen.findByRole('radio', { name: 'parts_v2.csv' }));
    expect(/** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Replace parts.csv' })).disabled).toBe(false);
    session.offline = true;
    flushSync();
    expect(screen.getByText(/cannot be replaced or restored/)).toBeTruthy();
    expect(/** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Replace parts.csv' })).disabled).toBe(true);
  });
});
