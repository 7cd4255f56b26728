// HTTP API of the database page: /api/database/... (session + page 'database' required).
import fsp from 'node:fs/promises';
import path from 'node:path';
import express, { Router } from 'express';
import multer from 'multer';
import { DatabaseError, FILE_NAME, DRIVE_ID, BACKUP_NAME, REL_PATH, REL_PATH_OR_ROOT, tooLarge } from './database-files.js';
import { errorBody, httpError, multipartError } from '../../core/http/errors.js';

/**
 * @param {{service: import('./database-files.js').DatabaseFiles, guard: import('express').RequestHandler[],
 *   uploadDir?: string, log?: (m: string) => void}} deps
 *   guard: session + page checks from the core (FeatureDeps.guard).
 *   uploadDir: where multipart uploads are spooled (default DATA_DIR/.uploads; one fresh directory per request, always removed).
 */
export function databaseRoutes({ service, guard, uploadDir, log = (m) => console.log(`[bff] ${m}`) }) {
  const spool = uploadDir || path.join(service.dataDir, '.uploads');
  const r = Router();
  const json = express.json({ limit: '16kb' });
  const actor = (req) => ({ username: req.session.username, role: req.session.role, ip: req.ip ?? req.socket?.remoteAddress ?? null });

  /** @param {(req: import('express').Request) => Promise<unknown>} fn @param {number} [okStatus] */
  const handle = (fn, okStatus = 200) => async (req, res) => {
    try {
      res.status(okStatus).json(await fn(req));
    } catch (e) {
      sendError(res, e, log);
    }
  };
  const body = (req, ...keys) => {
    if (!req.is('application/json')) throw new DatabaseError(415, 'expected application/json', 'request.not_json');
    const b = req.body;
    if (!b || typeof b !== 'object' || Array.isArray(b)) throw invalidRequest(400, 'expected a JSON object');
    for (const k of keys) if (typeof b[k] !== 'string' || b[k] === '') throw invalidRequest(400, `"${k}" must be a non-empty string`);
    return b;
  };

  r.get('/api/database/files', ...guard, handle(async () => ({ max_upload_bytes: service.maxBytes, files: await service.listTargets() })));
  r.get('/api/database/drives', ...guard, handle(async () => ({ drives: await service.listDrives() })));
  r.get('/api/database/drives/:drive/files', ...guard, handle(async (req) => {
    const p = req.query.path ?? '';
    if (typeof p !== 'string') throw new DatabaseError(400, 'invalid path', 'database.invalid_path');
    return service.listDriveFiles(param(req, 'drive'), p);
  }));
  r.post('/api/database/files/:name/from-drive', ...guard, json, handle(async (req) => {
    const b = body(req, 'drive', 'path');
    return service.replaceFromDrive(param(req, 'name'), b.drive, b.path, actor(req));
  }));
  r.get('/api/database/files/:name/backups', ...guard, handle(async (req) => ({ backups: await service.listBackups(param(req, 'name')) })));
  r.post('/api/database/files/:name/restore', ...guard, json, handle(async (req) => {
    const b = body(req, 'backup');
    return service.restoreBackup(param(req, 'name'), b.backup, actor(req));
  }));

  const upload = multer({
    storage: multer.diskStorage({
      destination: (req, file, cb) => cb(null, req.uploadDir),
      filename: (req, file, cb) => cb(null, 'upload'),
    }),
    limits: { fileSize: service.maxBytes, files: 1, fields: 4, parts: 6 },
  }).single('file');

  r.post('/api/database/files/:name/upload', ...guard, async (req, res) => {
    let dir = null;
    let received = false; // past this point the service audits
    let result;
    let error = null;
    try {
      // Unknown targets and names are refused before anything is received.
      await service.listBackups(param(req, 'name'));
      if (!req.is('multipart/form-data')) throw new DatabaseError(415, 'expected multipart/form-data with a field "file"', 'database.not_multipart');
      const declared = Number(req.headers['content-length']);
      if (Number.isFinite(declared) && declared > service.maxBytes + 64 * 1024) throw tooLarge(service.maxBytes);
      await fsp.mkdir(spool, { recursive: true, mode: 0o700 });
      dir = await fsp.mkdtemp(path.join(spool, 'up-'));
      req.uploadDir = dir;
      await new Promise((resolve, reject) => upload(req, res, (err) => (err ? reject(err) : resolve())));
      if (!req.file) throw new DatabaseError(400, 'no file in field "file"', 'database.no_file');
      received = true;
      result = await service.replaceFromUpload(param(req, 'name'), req.file.path, req.file.originalname, actor(req));
    } catch (e) {
      error = e instanceof DatabaseError || received ? e : uploadError(e, service.maxBytes);
      if (!received && error instanceof DatabaseError) {
        const a = actor(req);
        service.audit?.record({ user: a.username, role: a.role, ip: a.ip, op: 'database.replace', target: String(param(req, 'name')), outcome: 'denied', detail: `upload: ${error.message}` });
      }
    }
    // The spooled upload is gone before the answer goes out.
    if (dir) await fsp.rm(dir, { recursive: true, force: true }).catch((e) => log(`database: could not remove ${dir}: ${e.message}`));
    if (!error) return res.json(result);
    // Refused before reading the body: answer and close instead of reading it all.
    if (!dir) res.setHeader('Connection', 'close');
    sendError(res, error, log);
  });
  return r;
}

/** Express 5 types a path parameter as string | string[]; ours are single segments. @param {import('express').Request} req @param {string} k */
const param = (req, k) => String(req.params[k]);

/** A request the core's OpenAPI check would refuse too: the same code (request.invalid {detail}). @param {number} status @param {string} message */
const invalidRequest = (status, message) => new DatabaseError(status, message, 'request.invalid', { detail: message });

/**
 * What went wrong while receiving a multipart body: multer's limits and busboy's parse errors are the client's
 * (400, 413), file-system errors while spooling stay server errors. @param {any} e @param {number} max
 */
function uploadError(e, max) {
  if (e?.code === 'LIMIT_FILE_SIZE') return tooLarge(max);
  const m = multipartError(e);
  if (!m.clientError) return e;
  if (['LIMIT_UNEXPECTED_FILE', 'LIMIT_FILE_COUNT'].includes(e?.code)) {
    return new DatabaseError(m.status, `${m.message}; send one file, in the field "file"`, 'database.one_file');
  }
  return m.code ? new DatabaseError(m.status, m.message, m.code, m.params) : invalidRequest(m.status, m.message);
}

function sendError(res, e, log) {
  if (res.headersSent) return;
  if (e instanceof DatabaseError && e.status < 500) return res.status(e.status).json(e.code ? errorBody(e.message, e.code, e.params) : { error: e.message });
  const h = httpError(e);
  if (h.clientError) return res.status(h.status).json(h.code ? errorBody(h.message, h.code, h.params) : { error: h.message });
  log(`database: ${e?.stack || e}`);
  // A failed write says what failed (the old file is unchanged); other failures stay 'internal error'.
  res.status(500).json({ error: e instanceof DatabaseError ? e.message : 'internal error' });
}

/**
 * OpenAPI 3.1 path objects for these routes; the core merges every feature's into the document and adds what the
 * core answers around them (401, 403 page/cross-origin, 400/413/415 on bodies, 405). Names, drive ids, backups and
 * paths use the rules the checks use (database-files.js).
 */
export const databaseOpenApiPaths = (() => {
  const json = (schema) => ({ content: { 'application/json': { schema } } });
  // code and params: a stable code ("database.not_listed") and the values in the message, for the app to say in the user's language.
  const error = { type: 'object', required: ['error'], properties: { error: { type: 'string' }, code: { type: 'string' }, params: { type: 'object' } } };
  const err = (description) => ({ description, ...json(error) });
  const name = { name: 'name', in: 'path', required: true, description: 'A file listed in the cell file (database.files)', schema: { ...FILE_NAME } };
  const drive = { name: 'drive', in: 'path', required: true, description: 'Drive id from GET /api/database/drives (at most 255 bytes in UTF-8)', schema: { ...DRIVE_ID } };
  const target = {
    type: 'object', required: ['name', 'size', 'mtime', 'exists'],
    properties: { name: { type: 'string' }, size: { type: ['integer', 'null'] }, mtime: { type: ['string', 'null'], format: 'date-time' }, exists: { type: 'boolean' } },
  };
  const replaced = {
    type: 'object', required: ['file', 'backup'],
    properties: { file: target, backup: { type: ['string', 'null'], description: 'Name of the backup of the old file (null when there was none)' } },
  };
  const outside = err('Role may not use the database page, or the path leads outside the drive (symbolic links) or is not readable');
  const writeFailed = err('Writing failed; the old file is unchanged');
  return {
    '/api/database/files': {
      get: {
        summary: 'Database files that may be replaced', security: [{ session: [] }],
        responses: { 200: { description: 'Files', ...json({ type: 'object', required: ['files'], properties: { max_upload_bytes: { type: 'integer' }, files: { type: 'array', items: target } } }) } },
      },
    },
    '/api/database/drives': {
      get: {
        summary: 'USB drives currently present', security: [{ session: [] }],
        responses: {
          200: { description: 'Drives', ...json({ type: 'object', required: ['drives'], properties: { drives: { type: 'array', items: {
            type: 'object', required: ['id', 'label', 'path'], properties: { id: { type: 'string', description: 'The id the drive routes take' }, label: { type: 'string' }, path: { type: 'string' } },
          } } } }) },
        },
      },
    },
    '/api/database/drives/{drive}/files': {
      get: {
        summary: 'Directories and files on a drive', security: [{ session: [] }],
        parameters: [drive, { name: 'path', in: 'query', required: false, description: 'Directory relative to the drive root (empty: the root)', schema: { ...REL_PATH_OR_ROOT } }],
        responses: {
          200: { description: 'Listing', ...json({ type: 'object', required: ['drive', 'path', 'entries'], properties: {
            drive: { type: 'string' }, path: { type: 'string' },
            entries: { type: 'array', items: { type: 'object', required: ['name', 'type'], properties: {
              name: { type: 'string' }, type: { enum: ['dir', 'file'] }, size: { type: 'integer' }, mtime: { type: 'string', format: 'date-time' },
              targets: { type: 'array', items: { type: 'string' }, description: 'Database files this file could replace (same extension)' },
            } } },
          } }) },
          400: err('Invalid drive id or path, or not a directory'), 403: outside, 404: err('Unknown drive or path'),
        },
      },
    },
    '/api/database/files/{name}/from-drive': {
      post: {
        summary: 'Replace a database file with a file from a USB drive (old file kept as a backup)', security: [{ session: [] }],
        parameters: [name],
        requestBody: { required: true, ...json({ type: 'object', additionalProperties: false, required: ['drive', 'path'],
          properties: { drive: { ...DRIVE_ID, description: 'Drive id from GET /api/database/drives' }, path: { ...REL_PATH, description: 'File path relative to the drive root' } } }) },
        responses: {
          200: { description: 'Replaced', ...json(replaced) },
          400: err('Invalid name, drive id or path, or not a file'), 403: outside, 404: err('Unknown file, drive or path'),
          413: err('File larger than database.max_upload_bytes'), 415: err('Wrong file extension'),
          422: err('Content does not parse (CSV, JSON, YAML)'), 500: writeFailed,
        },
      },
    },
    '/api/database/files/{name}/upload': {
      post: {
        summary: 'Replace a database file with an uploaded file (old file kept as a backup)', security: [{ session: [] }],
        parameters: [name],
        requestBody: { required: true, content: { 'multipart/form-data': { schema: { type: 'object', required: ['file'], properties: { file: { type: 'string', format: 'binary' } } } } } },
        responses: {
          200: { description: 'Replaced', ...json(replaced) },
          400: err('Invalid name; no file in the field "file"; a malformed multipart body; more than one file, or too many fields'),
          404: err('Unknown file'), 413: err('File larger than database.max_upload_bytes'),
          415: err('Not multipart/form-data, or wrong file extension'), 422: err('Content does not parse (CSV, JSON, YAML)'), 500: writeFailed,
        },
      },
    },
    '/api/database/files/{name}/backups': {
      get: {
        summary: 'Backups of a database file, newest first', security: [{ session: [] }],
        parameters: [name],
        responses: {
          200: { description: 'Backups', ...json({ type: 'object', required: ['backups'], properties: { backups: { type: 'array', items: {
            type: 'object', required: ['name', 'size', 'mtime'], properties: { name: { ...BACKUP_NAME }, size: { type: 'integer' }, mtime: { type: 'string', format: 'date-time' } },
          } } } }) },
          400: err('Invalid name'), 404: err('Unknown file'),
        },
      },
    },
    '/api/database/files/{name}/restore': {
      post: {
        summary: 'Restore a backup (the current file is backed up first)', security: [{ session: [] }],
        parameters: [name],
        requestBody: { required: true, ...json({ type: 'object', additionalProperties: false, required: ['backup'],
          properties: { backup: { ...BACKUP_NAME, description: 'A backup of this file, as listed by GET .../backups ("<name>.<time>")' } } }) },
        responses: {
          200: { description: 'Restored', ...json(replaced) },
          400: err('Invalid name or backup name'), 404: err('Unknown file or backup'), 500: writeFailed,
        },
      },
    },
  };
})();
