/**
 * The database feature's plain logic (no Svelte): the API calls (JSON through core/api.js, uploads through
 * XMLHttpRequest for their progress), the replace/restore flow as a small state machine, and the texts the page
 * shows (confirmations name both files). The BFF does every check (listed targets, same extension, content,
 * size, paths); the page shows its answers as they come. The texts come from messages/database; sizes, dates and
 * percentages are in the user's locale.
 *
 * API (bff/src/features/database/routes.js): GET /api/database/files, GET /api/database/drives,
 * GET /api/database/drives/:drive/files?path=, POST /api/database/files/:name/from-drive {drive, path},
 * POST /api/database/files/:name/upload (multipart, field "file"), GET /api/database/files/:name/backups,
 * POST /api/database/files/:name/restore {backup}.
 */
import { m } from '$lib/paraglide/messages.js';
import { request } from '../../core/api.js';
import { errorText } from '../../core/errors.js';
import { fmtNumber, fmtFixed, fmtDateTime, getLocale } from '../../core/i18n.js';

export const FEATURE_ID = 'database';

/** @typedef {{ name: string, size: number | null, mtime: string | null, exists: boolean }} TargetInfo */
/** @typedef {{ id: string, label: string, path: string }} Drive */
/** @typedef {{ name: string, type: 'dir' | 'file', size?: number, mtime?: string, targets?: string[] }} DriveEntry */
/** @typedef {{ name: string, size: number, mtime: string }} Backup */
/** @typedef {{ file: TargetInfo, backup: string | null }} Replaced */
/** A file picked on a drive: the drive, its path relative to the drive, its name and size. @typedef {{ drive: Drive, path: string, name: string, size: number | null }} DrivePick */

const enc = encodeURIComponent;

export const databaseApi = {
  files: () => request('GET', '/api/database/files'),
  drives: () => request('GET', '/api/database/drives'),
  /** @param {string} drive @param {string} [path] */
  driveFiles: (drive, path = '') => request('GET', `/api/database/drives/${enc(drive)}/files${path ? `?path=${enc(path)}` : ''}`),
  /** @param {string} target @param {string} drive @param {string} path */
  fromDrive: (target, drive, path) => request('POST', `/api/database/files/${enc(target)}/from-drive`, { drive, path }),
  /** @param {string} target */
  backups: (target) => request('GET', `/api/database/files/${enc(target)}/backups`),
  /** @param {string} target @param {string} backup */
  restore: (target, backup) => request('POST', `/api/database/files/${enc(target)}/restore`, { backup }),
  /** @param {string} target @param {Blob & { name?: string }} file @param {(p: Progress) => void} [onProgress] */
  upload: (target, file, onProgress) => uploadFile(`/api/database/files/${enc(target)}/upload`, file, { onProgress }),
};

/** @typedef {{ loaded: number, total: number, fraction: number | null }} Progress */

/**
 * POST one file as multipart/form-data (field "file") with XMLHttpRequest, reporting upload progress.
 * Resolves like core/api.js request(): never rejects.
 * @param {string} url @param {Blob & { name?: string }} file
 * @param {{ onProgress?: (p: Progress) => void, field?: string, xhr?: () => XMLHttpRequest }} [o]
 * @returns {Promise<import('../../core/api.js').ApiResult>}
 */
export function uploadFile(url, file, o = {}) {
  const xhr = (o.xhr ?? (() => new XMLHttpRequest()))();
  const form = new FormData();
  form.append(o.field ?? 'file', file, file.name ?? 'upload');
  return new Promise((resolve) => {
    xhr.open('POST', url);
    xhr.withCredentials = true;
    xhr.setRequestHeader('Accept', 'application/json');
    xhr.upload.onprogress = (e) => {
      const total = e.lengthComputable ? e.total : file.size;
      o.onProgress?.({ loaded: e.loaded, total, fraction: total > 0 ? Math.min(1, e.loaded / total) : null });
    };
    xhr.onload = () => {
      let data = null;
      try {
        data = xhr.responseText ? JSON.parse(xhr.responseText) : null;
      } catch {
        data = null;
      }
      const status = xhr.status;
      if (status >= 200 && status < 300) return resolve({ kind: 'ok', status, data });
      const error = errorText(data) || xhr.statusText || `HTTP ${status}`;
      if (status === 401) return resolve({ kind: 'unauthorized', status: 401, error, data });
      if (status === 403) return resolve({ kind: 'forbidden', status: 403, error, data });
      resolve({ kind: 'error', status, error, data });
    };
    // The server may answer a refusal and close before the body is sent (e.g. 413): that is an error event.
    xhr.onerror = () => resolve({ kind: 'offline', error: m.database_upload_lost() });
    xhr.onabort = () => resolve({ kind: 'offline', error: m.database_upload_cancelled() });
    xhr.send(form);
  });
}

// ---- the replace / restore flow ----

/**
 * idle -> confirm (the question naming both files) -> running (progress for uploads) -> done | failed.
 * Cancel at confirm goes back to idle; done/failed stay until the next ask (or a reset).
 * @typedef {{ phase: 'idle' }
 *   | { phase: 'confirm', kind: 'replace' | 'restore', target: string, source: string, question: string }
 *   | { phase: 'running', kind: 'replace' | 'restore', target: string, source: string, progress: number | null }
 *   | { phase: 'done', kind: 'replace' | 'restore', target: string, source: string, message: string, backup: string | null }
 *   | { phase: 'failed', kind: 'replace' | 'restore', target: string, source: string, error: string }} Flow
 */

/**
 * @typedef {{ type: 'ask', kind: 'replace' | 'restore', target: string, source: string }
 *   | { type: 'cancel' } | { type: 'confirm' } | { type: 'progress', fraction: number | null }
 *   | { type: 'ok', result: Replaced } | { type: 'fail', error: string } | { type: 'reset' }} FlowEvent
 */

/** @type {Flow} */
export const IDLE = Object.freeze({ phase: 'idle' });

/**
 * @param {Flow} s @param {FlowEvent} e
 * @returns {Flow}
 */
export function step(s, e) {
  switch (e.type) {
    case 'ask':
      if (s.phase === 'running') return s; // one at a time
      return { phase: 'confirm', kind: e.kind, target: e.target, source: e.source, question: question(e.kind, e.target, e.source) };
    case 'cancel':
      return s.phase === 'confirm' ? IDLE : s;
    case 'confirm':
      return s.phase === 'confirm' ? { phase: 'running', kind: s.kind, target: s.target, source: s.source, progress: null } : s;
    case 'progress':
      return s.phase === 'running' ? { ...s, progress: e.fraction } : s;
    case 'ok':
      if (s.phase !== 'running') return s;
      return { phase: 'done', kind: s.kind, target: s.target, source: s.source, backup: e.result?.backup ?? null, message: doneText(s.kind, s.target, s.source, e.result) };
    case 'fail':
      if (s.phase !== 'running') return s;
      return { phase: 'failed', kind: s.kind, target: s.target, source: s.source, error: e.error || m.database_server_refused() };
    case 'reset':
      return s.phase === 'running' ? s : IDLE;
    default:
      return s;
  }
}

/** @param {'replace' | 'restore'} kind @param {string} target @param {string} source */
export function question(kind, target, source) {
  return kind === 'replace' ? m.database_ask_replace({ target, source }) : m.database_ask_restore({ target, source });
}

/**
 * What the confirmation adds below its question: what happens to the current file (the BFF backs it up before a
 * replace or a restore, when there is one).
 * @param {string} target @param {boolean} exists
 */
export function confirmNote(target, exists) {
  return exists ? m.database_note_backup({ target }) : m.database_note_no_backup({ target });
}

/** @param {'replace' | 'restore'} kind @param {string} target @param {string} source @param {Replaced | undefined} r */
export function doneText(kind, target, source, r) {
  const backup = r?.backup;
  if (kind === 'replace') {
    return backup ? m.database_replaced_backup({ target, source, backup }) : m.database_replaced_no_backup({ target, source });
  }
  return backup ? m.database_restored_backup({ target, source, backup }) : m.database_restored_no_backup({ target, source });
}

/** @param {'replace' | 'restore'} kind @param {string} target @param {string} error */
export const failText = (kind, target, error) =>
  kind === 'replace' ? m.database_replace_failed({ target, error }) : m.database_restore_failed({ target, error });

// ---- names, paths and texts ----

/** ".csv" (lower case), '' without one. @param {string} name */
export function extOf(name) {
  const base = String(name ?? '').split('/').pop() ?? '';
  const i = base.lastIndexOf('.');
  return i > 0 ? base.slice(i).toLowerCase() : '';
}

/**
 * The target to preselect for a source file: the first listed target with its extension ('' when none).
 * @param {string} fileName @param {string[]} targets
 */
export function defaultTarget(fileName, targets) {
  const e = extOf(fileName);
  return targets.find((t) => extOf(t) === e) ?? '';
}

/**
 * A warning when the source's extension differs from the target's (the server refuses it; the page says so
 * before, and shows the server's answer if it is sent anyway).
 * @param {string} fileName @param {string} target
 */
export function extensionWarning(fileName, target) {
  if (!fileName || !target) return '';
  const a = extOf(fileName), b = extOf(target);
  if (a === b) return '';
  if (!b) return m.database_ext_target_none({ target, file: fileName, fileExt: a });
  if (!a) return m.database_ext_file_none({ target, ext: b, file: fileName });
  return m.database_ext_mismatch({ target, ext: b, file: fileName, fileExt: a });
}

/** The accept attribute of the file picker: the targets' extensions. @param {string[]} targets */
export const acceptFor = (targets) => [...new Set(targets.map(extOf).filter(Boolean))].join(',');

/** "/media/usb1" + "dir/parts.csv" -> "/media/usb1/dir/parts.csv". @param {string} root @param {string} rel */
export function joinPath(root, rel) {
  const r = String(root ?? '').replace(/\/+$/, '');
  const p = String(rel ?? '').replace(/^\/+/, '');
  return p ? `${r}/${p}` : r || '/';
}

/** The folder above a relative path ('' at the drive's root). @param {string} rel */
export function parentPath(rel) {
  const parts = String(rel ?? '').split('/').filter(Boolean);
  parts.pop();
  return parts.join('/');
}

/** @param {string} dir @param {string} name */
export const childPath = (dir, name) => (dir ? `${dir.replace(/\/+$/, '')}/${name}` : name);

/** "1.2 KB", "3.4 MB", "512 B". @param {number | null | undefined} n */
export function formatBytes(n) {
  if (typeof n !== 'number' || !Number.isFinite(n) || n < 0) return '—';
  if (n < 1024) return `${fmtNumber(n)} B`;
  if (n < 1024 * 1024) return `${fmtFixed(n / 1024, 1)} KB`;
  return `${fmtFixed(n / 1024 / 1024, 1)} MB`;
}

/** @type {Intl.DateTimeFormatOptions} */
const DATE_OPTS = { day: 'numeric', month: 'short', year: 'numeric', hour: '2-digit', minute: '2-digit', second: '2-digit', hourCycle: 'h23' };
/** English keeps its day-month-year, 24-hour form; the other languages get their own. */
const EN_DATE = new Intl.DateTimeFormat('en-GB', DATE_OPTS);

/** "22 Nov 2026, 14:03:21" (local time, in the user's locale: "22. Nov. 2026, 14:03:21" in German). @param {string | number | null | undefined} t */
export function formatDate(t) {
  if (t === null || t === undefined || t === '') return '—';
  const d = new Date(t);
  if (Number.isNaN(d.getTime())) return '—';
  return getLocale() === 'en' ? EN_DATE.format(d) : fmtDateTime(d, DATE_OPTS);
}

/** When a backup was made, from its name ("parts.csv.2026-11-22T10:10:10.000Z-1"), else null. @param {string} target @param {string} name */
export function backupTime(target, name) {
  if (!name.startsWith(`${target}.`)) return null;
  const stamp = name.slice(target.length + 1).replace(/-\d+$/, '');
  const ms = Date.parse(stamp);
  return Number.isFinite(ms) ? ms : null;
}

/** "45 %" for a fraction, '' when unknown. @param {number | null} f */
export const percent = (f) => (typeof f === 'number' && Number.isFinite(f) ? `${fmtNumber(Math.round(f * 100))} %` : '');
