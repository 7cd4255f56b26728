import { describe, it, expect, vi } from 'vitest';
import {
  step, IDLE, question, confirmNote, doneText, failText, extOf, defaultTarget, extensionWarning, acceptFor, joinPath, parentPath, childPath,
  formatBytes, backupTime, percent, uploadFile,
} from '../../../src/lib/features/database/logic.js';

/** @param {import('../../../src/lib/features/database/logic.js').Flow} s @param {...any} evs */
const run = (s, ...evs) => evs.reduce((acc, e) => step(acc, e), s);

describe('the replace / restore flow', () => {
  it('replace: confirm names both files, then running with progress, then the result with the backup', () => {
    let s = step(IDLE, { type: 'ask', kind: 'replace', target: 'parts.csv', source: '/media/usb1/parts_v2.csv' });
    expect(s).toMatchObject({ phase: 'confirm', question: 'Replace parts.csv with /media/usb1/parts_v2.csv?' });
    s = run(s, { type: 'confirm' }, { type: 'progress', fraction: 0.45 });
    expect(s).toMatchObject({ phase: 'running', progress: 0.45, target: 'parts.csv' });
    // A second request while one runs is ignored (one at a time).
    expect(step(s, { type: 'ask', kind: 'replace', target: 'fixtures.yaml', source: 'x' })).toBe(s);
    expect(step(s, { type: 'reset' })).toBe(s);
    s = step(s, { type: 'ok', result: { file: { name: 'parts.csv', size: 10, mtime: '', exists: true }, backup: 'parts.csv.2026-11-22T10:00:00.000Z' } });
    expect(s).toMatchObject({ phase: 'done', backup: 'parts.csv.2026-11-22T10:00:00.000Z' });
    expect(s.phase === 'done' && s.message).toBe('parts.csv replaced with /media/usb1/parts_v2.csv. The file it replaced was kept as the backup parts.csv.2026-11-22T10:00:00.000Z.');
    expect(step(s, { type: 'reset' })).toBe(IDLE);
  });

  it('cancel at the confirmation sends nothing; a failure keeps the server message', () => {
    const asked = step(IDLE, { type: 'ask', kind: 'restore', target: 'parts.csv', source: 'parts.csv.2026-11-22T10:00:00.000Z' });
    expect(asked.phase === 'confirm' && asked.question).toBe('Restore parts.csv from the backup parts.csv.2026-11-22T10:00:00.000Z?');
    expect(step(asked, { type: 'cancel' })).toBe(IDLE);
    // Events out of place change nothing.
    expect(step(IDLE, { type: 'confirm' })).toBe(IDLE);
    expect(step(IDLE, { type: 'ok', result: { file: /** @type {any} */ ({}), backup: null } })).toBe(IDLE);
    const failed = run(asked, { type: 'confirm' }, { type: 'fail', error: 'parts.csv needs a .csv file, not .txt' });
    expect(failed).toMatchObject({ phase: 'failed', error: 'parts.csv needs a .csv file, not .txt' });
    expect(failText('replace', 'parts.csv', 'nope')).toBe('Could not replace parts.csv: nope');
    expect(failText('restore', 'parts.csv', 'nope')).toBe('Could not restore parts.csv: nope');
    expect(doneText('restore', 'parts.csv', 'b1', { file: /** @type {any} */ ({}), backup: null })).toBe('parts.csv restored from b1. There was no earlier file to back up.');
    expect(question('replace', 'a.csv', 'b.csv from this device')).toBe('Replace a.csv with b.csv from this device?');
    expect(confirmNote('a.csv', true)).toBe('The current a.csv is kept as a backup, which can be restored.');
    expect(confirmNote('a.csv', false)).toBe('There is no a.csv on the robot PC yet, so there is nothing to back up.');
  });
});

describe('names and paths', () => {
  it('extensions, the preselected target, the warning and the picker filter', () => {
    expect(extOf('/media/usb/Parts_V2.CSV')).toBe('.csv');
    expect(extOf('README')).toBe('');
    expect(extOf('.hidden')).toBe('');
    expect(defaultTarget('new.yaml', ['parts.csv', 'fixtures.yaml'])).toBe('fixtures.yaml');
    expect(defaultTarget('x.txt', ['parts.csv'])).toBe('');
    expect(extensionWarning('parts_v2.csv', 'parts.csv')).toBe('');
    expect(extensionWarning('notes.txt', 'parts.csv')).toBe('parts.csv takes only .csv files; notes.txt is .txt.');
    expect(acceptFor(['parts.csv', 'fixtures.yaml', 'more.csv'])).toBe('.csv,.yaml');
  });
  it('drive paths', () => {
    expect(joinPath('/media/usb1/', 'db/parts_v2.csv')).toBe('/media/usb1/db/parts_v2.csv');
    expect(joinPath('/media/usb1', '')).toBe('/media/usb1');
    expect(parentPath('a/b/c')).toBe('a/b');
    expect(parentPath('a')).toBe('');
    expect(childPath('', 'a')).toBe('a');
    expect(childPath('a/', 'b')).toBe('a/b');
  });
  it('sizes, backup times, percentages', () => {
    expect(formatBytes(512)).toBe('512 B');
    expect(formatBytes(2048)).toBe('2.0 KB');
    expect(formatBytes(3 * 1024 * 1024)).toBe('3.0 MB');
    expect(formatBytes(null)).toBe('—');
    expect(backupTime('parts.csv', 'parts.csv.2026-11-22T10:00:00.000Z')).toBe(Date.parse('2026-11-22T10:00:00.000Z'));
    expect(backupTime('parts.csv', 'parts.csv.2026-11-22T10:00:00.000Z-2')).toBe(Date.parse('2026-11-22T10:00:00.000Z'));
    expect(backupTime('parts.csv', 'other.csv.2026')).toBeNull();
    expect(percent(0.456)).toBe('46 %');
    expect(percent(null)).toBe('');
  });
});

/** A scripted XMLHttpRequest. */
function fakeXhr({ status = 200, body = '{}', fail = false } = {}) {
  const x = /** @type {any} */ ({
    upload: {},
    headers: /** @type {Record<string, string>} */ ({}),
    open: vi.fn((/** @type {string} */ m, /** @type {string} */ u) => { x.method = m; x.url = u; }),
    setRequestHeader: (/** @type {string} */ k, /** @type {string} */ v) => { x.headers[k] = v; },
    send: vi.fn((/** @type {FormData} */ form) => {
      x.form = form;
      x.upload.onprogress?.({ loaded: 50, total: 200, lengthComputable: true });
      x.upload.onprogress?.({ loaded: 200, total: 200, lengthComputable: true });
      if (fail) return x.onerror?.();
      x.status = status;
      x.responseText = body;
      x.onload?.();
    }),
  });
  return x;
}

describe('uploadFile: XMLHttpRequest with progress', () => {
  it('posts the file as multipart field "file", reports progress, resolves with the JSON answer', async () => {
    const x = fakeXhr({ body: JSON.stringify({ file: { name: 'parts.csv' }, backup: 'b' }) });
    const seen = /** @type {number[]} */ ([]);
    const file = new File(['a,b\n1,2\n'], 'parts_v2.csv', { type: 'text/csv' });
    const r = await uploadFile('/api/database/files/parts.csv/upload', file, { onProgress: (p) => seen.push(/** @type {number} */ (p.fraction)), xhr: () => x });
    expect(x.method).toBe('POST');
    expect(x.url).toBe('/api/database/files/parts.csv/upload');
    expect(/** @type {File} */ (x.form.get('file')).name).toBe('parts_v2.csv');
    expect(seen).toEqual([0.25, 1]);
    expect(r).toMatchObject({ kind: 'ok', status: 200, data: { backup: 'b' } });
  });
  it("the server's refusal as it came; a dropped connection is an error too", async () => {
    const file = new File(['x'], 'notes.txt');
    const r = await uploadFile('/u', file, { xhr: () => fakeXhr({ status: 415, body: JSON.stringify({ error: 'parts.csv needs a .csv file, not .txt' }) }) });
    expect(r).toMatchObject({ kind: 'error', status: 415, error: 'parts.csv needs a .csv file, not .txt' });
    expect((await uploadFile('/u', file, { xhr: () => fakeXhr({ status: 403, body: '{"error":"no"}' }) })).kind).toBe('forbidden');
    expect((await uploadFile('/u', file, { xhr: () => fakeXhr({ fail: true }) })).kind).toBe('offline');
  });
});
