// System (administration): health, the cell file, roles, users, and the audit log. HTTP only.
import { Router } from 'express';
import { defineFeature } from '../../core/features/feature.js';

const json = (schema) => ({ content: { 'application/json': { schema } } });
const error = { type: 'object', required: ['error'], properties: { error: { type: 'string' } } };
const unauthorized = { description: 'Not logged in', ...json(error) };
const forbidden = { description: 'Role may not use the System page', ...json(error) };

export default defineFeature({
  id: 'system',
  title: 'System',
  routes: ({ cell, cellFile, users, audit, healthReport, guard }) => {
    const r = Router();
    r.get('/api/system', ...guard, async (req, res) => {
      res.json({
        cell_file: cellFile,
        cell: cell.cell,
        roles: Object.entries(cell.roles).map(([name, def]) => ({ name, title: def.title || name, pages: def.pages, commands: def.commands || [] })),
        users: users.list(),
        health: await healthReport(),
      });
    });
    r.get('/api/audit', ...guard, (req, res) => {
      const q = req.query;
      const num = (v, d, max) => { const n = Number(v); return Number.isInteger(n) && n >= 0 ? Math.min(n, max) : d; };
      res.json(audit.query({
        user: typeof q.user === 'string' ? q.user : undefined,
        op: typeof q.op === 'string' ? q.op : undefined,
        outcome: typeof q.outcome === 'string' ? q.outcome : undefined,
        since: typeof q.since === 'string' ? q.since : undefined,
        offset: num(q.offset, 0, 1e9),
        limit: num(q.limit, 50, 500) || 50,
      }));
    });
    return r;
  },
  openapi: {
    '/api/system': {
      get: { summary: 'System overview: health, cell file, roles, users', security: [{ session: [] }], responses: { 200: { description: 'Overview', ...json({ type: 'object' }) }, 401: unauthorized, 403: forbidden } },
    },
    '/api/audit': {
      get: {
        summary: 'Audit log, newest first (System page roles)', security: [{ session: [] }],
        parameters: ['user', 'op', 'outcome', 'since', 'offset', 'limit'].map((name) => ({ name, in: 'query', required: false, schema: { type: 'string' } })),
        responses: { 200: { description: 'A page of entries', ...json({ type: 'object', required: ['total', 'entries'], properties: { total: { type: 'integer' }, offset: { type: 'integer' }, limit: { type: 'integer' }, entries: { type: 'array' } } }) }, 401: unauthorized, 403: forbidden },
      },
    },
  },
});
