// HTTP API of the Recordings page: /api/recorder/... (session + page 'recorder' required). Downloads and deletes
// go to the audit log; saves are rosbridge calls of /cell/recorder/save, audited by the op guard.
import { pipeline } from 'node:stream/promises';
import { Router } from 'express';
import { RecordingError, RECORDING_NAME } from './recordings.js';
import { errorBody, httpError } from '../../core/http/errors.js';

/**
 * @param {{recordings: import('./recordings.js').Recordings, canDelete: (role: string) => boolean,
 *   guard: import('express').RequestHandler[], audit: import('../../core/audit/audit-log.js').AuditLog,
 *   log?: (m: string) => void}} deps
 */
export function recorderRoutes({ recordings, canDelete, guard, audit, log = (m) => console.log(`[bff] ${m}`) }) {
  const r = Router();
  const name = (req) => String(req.params.name);
  /** @param {import('express').Request} req @param {string} op @param {'ok'|'denied'} outcome @param {string} [detail] */
  const record = (req, op, outcome, detail) => audit.record({
    user: req.session.username, role: req.session.role, ip: req.ip ?? req.socket?.remoteAddress ?? null,
    op, target: name(req), outcome, detail,
  });
  /** @param {import('express').Response} res @param {any} e */
  const fail = (res, e) => {
    if (res.headersSent) return void res.destroy();
    if (e instanceof RecordingError) return void res.status(e.status).json(e.code ? errorBody(e.message, e.code, e.params) : { error: e.message });
    const h = httpError(e);
    if (!h.clientError) log(`recorder: ${e?.stack || e}`);
    res.status(h.status).json(!h.clientError ? { error: 'internal error' } : h.code ? errorBody(h.message, h.code, h.params) : { error: h.message });
  };

  r.get('/api/recorder/recordings', ...guard, async (req, res) => {
    try {
      res.json({ recordings: await recordings.list(), can_delete: canDelete(req.session.role) });
    } catch (e) {
      fail(res, e);
    }
  });
  r.get('/api/recorder/recordings/:name', ...guard, async (req, res) => {
    try {
      res.json(await recordings.describe(name(req)));
    } catch (e) {
      fail(res, e);
    }
  });
  r.get('/api/recorder/recordings/:name/file', ...guard, async (req, res) => {
    let file;
    try {
      file = await recordings.open(name(req));
    } catch (e) {
      if (e instanceof RecordingError) await record(req, 'recorder.download', 'denied', e.message);
      return fail(res, e);
    }
    await record(req, 'recorder.download', 'ok');
    res.set({
      'Content-Type': 'application/octet-stream', 'Content-Length': String(file.size),
      'Content-Disposition': `attachment; filename="${name(req)}"`, 'Cache-Control': 'no-store',
    });
    try {
      await pipeline(file.stream, res);
    } catch (e) {
      if (!res.writableEnded) log(`recorder: download of ${name(req)} cut: ${/** @type {Error} */ (e).message}`);
    }
  });
  r.delete('/api/recorder/recordings/:name', ...guard, async (req, res) => {
    try {
      if (!canDelete(req.session.role)) throw new RecordingError(403, `role ${req.session.role} may not delete recordings`, 'recorder.delete_denied', { role: req.session.role });
      await recordings.remove(name(req));
      await record(req, 'recorder.delete', 'ok');
      res.json({ deleted: name(req) });
    } catch (e) {
      if (e instanceof RecordingError) await record(req, 'recorder.delete', 'denied', e.message);
      fail(res, e);
    }
  });
  return r;
}

/** OpenAPI 3.1 paths of these routes (the core adds 401, 403 for the page, 405). */
export const recorderOpenApiPaths = (() => {
  const json = (schema) => ({ content: { 'application/json': { schema } } });
  // code and params: a stable code ("recorder.not_found") and the values in the message, for the app to say in the user's language.
  const err = (description) => ({ description, ...json({ type: 'object', required: ['error'], properties: { error: { type: 'string' }, code: { type: 'string' }, params: { type: 'object' } } }) });
  const name = { name: 'name', in: 'path', required: true, description: 'A recording\'s file name', schema: { ...RECORDING_NAME } };
  const recording = {
    type: 'object', required: ['name', 'at_ms', 'reason', 'size', 'duration_s', 'messages', 'alarms'],
    properties: {
      name: { type: 'string' }, at_ms: { type: 'number', description: 'The alarm\'s (or the save request\'s) time, ms since the epoch' },
      reason: { type: 'string', description: '"alarm <id>: <text>", "saved by hand"; "" unknown (no description)' },
      size: { type: 'integer' }, duration_s: { type: 'number' }, messages: { type: 'integer' }, alarms: { type: 'array', items: { type: 'string' } },
    },
  };
  const detail = {
    ...recording, required: [...recording.required, 'start_ms', 'end_ms', 'topics', 'timeline'],
    properties: {
      ...recording.properties, start_ms: { type: 'number' }, end_ms: { type: 'number' },
      topics: { type: 'array', items: { type: 'object', required: ['topic', 'type', 'count'], properties: { topic: { type: 'string' }, type: { type: 'string' }, count: { type: 'integer' } } } },
      timeline: { type: 'object', required: ['lanes'], properties: { lanes: { type: 'array', items: {
        type: 'object', required: ['id', 'title', 'changes'],
        properties: { id: { enum: ['alarms', 'process', 'mode'] }, title: { type: 'string' }, changes: { type: 'array', items: {
          type: 'object', required: ['t_ms', 'text'], properties: { t_ms: { type: 'number' }, text: { type: 'string' } },
        } } },
      } } } },
    },
  };
  return {
    '/api/recorder/recordings': {
      get: {
        summary: 'The flight recorder\'s recordings, newest first', security: [{ session: [] }],
        responses: { 200: { description: 'Recordings', ...json({ type: 'object', required: ['recordings', 'can_delete'], properties: { recordings: { type: 'array', items: recording }, can_delete: { type: 'boolean' } } }) } },
      },
    },
    '/api/recorder/recordings/{name}': {
      get: {
        summary: 'One recording with its topics and timeline', security: [{ session: [] }], parameters: [name],
        responses: { 200: { description: 'The recording', ...json(detail) }, 400: err('Not a recording\'s name'), 404: err('No such recording') },
      },
      delete: {
        summary: 'Delete a recording (roles in recorder.delete_roles)', security: [{ session: [] }], parameters: [name],
        responses: {
          200: { description: 'Deleted', ...json({ type: 'object', required: ['deleted'], properties: { deleted: { type: 'string' } } }) },
          400: err('Not a recording\'s name'), 403: err('The role may not delete recordings'), 404: err('No such recording'),
        },
      },
    },
    '/api/recorder/recordings/{name}/file': {
      get: {
        summary: 'Download a recording (MCAP, ROS 1 profile)', security: [{ session: [] }], parameters: [name],
        responses: {
          200: { description: 'The MCAP file', content: { 'application/octet-stream': { schema: { type: 'string', format: 'binary' } } } },
          400: err('Not a recording\'s name'), 404: err('No such recording'),
        },
      },
    },
  };
})();
