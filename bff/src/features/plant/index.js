// Plant: the cell reports itself on the plant's MQTT broker as a Sparkplug B edge node (NBIRTH/NDATA/NDEATH, read
// only: nothing on MQTT commands the cell), and the plant page shows every cell of the plant's groups, live, for the
// roles the cell file grants it. Why in the BFF and not a ROS node: the BFF is what a user reaches, so its death is
// what the plant must see (the broker's will), and it already holds the cell file. docs/plant.md.
import { Router } from 'express';
import { defineFeature, featureSchema } from '../../core/features/feature.js';
import { PlantService } from './service.js';

const json = (/** @type {object} */ schema) => ({ content: { 'application/json': { schema } } });
const error = { type: 'object', required: ['error'], properties: { error: { type: 'string' } } };
const guarded = { 401: { description: 'Not logged in', ...json(error) }, 403: { description: 'Role may not see the plant page', ...json(error) } };

export default defineFeature({
  id: 'plant',
  title: 'Plant',
  schema: featureSchema('plant'),
  // The page shows other cells, not this one: a cell that only reports needs no page, so the section is optional.
  sectionRequired: false,
  view: (section) => ({ groups: section?.groups ?? (section ? [section.group_id] : []) }),
  routes: ({ cell, section, env, guard, log, onClose, addHealth }) => {
    const r = Router();
    if (!section) {
      r.get(['/api/plant/cells', '/api/plant/events'], ...guard, (req, res) => res.status(404).json({ error: 'this cell file has no plant section (no broker)' }));
      return r;
    }
    const view = Object.values(cell.roles).some((/** @type {any} */ role) => role.pages?.includes('plant'));
    const plant = new PlantService({ section, cell, env, view, log });
    onClose(() => plant.close());
    addHealth('plant', () => plant.health());
    r.get('/api/plant/cells', ...guard, (req, res) => res.json(plant.snapshot()));
    r.get('/api/plant/events', ...guard, (req, res) => {
      res.writeHead(200, { 'Content-Type': 'text/event-stream', 'Cache-Control': 'no-store', Connection: 'keep-alive', 'X-Accel-Buffering': 'no' });
      /** @type {NodeJS.Timeout | null} */
      let timer = null;
      let last = 0;
      const send = () => {
        timer = null;
        last = Date.now();
        res.write(`event: cells\ndata: ${JSON.stringify(plant.snapshot())}\n\n`);
      };
      // At most 10 snapshots a second, the newest always sent.
      const changed = () => { if (!timer) timer = setTimeout(send, Math.max(0, last + 100 - Date.now())); };
      const ping = setInterval(() => res.write(': keep-alive\n\n'), 15_000);
      const off = plant.subscribe(changed);
      send();
      req.on('close', () => { off(); clearInterval(ping); if (timer) clearTimeout(timer); });
    });
    return r;
  },
  openapi: {
    '/api/plant/cells': {
      get: {
        summary: 'Every cell of the plant the broker knows (Sparkplug B edge nodes): online, mode, alarms, process', security: [{ session: [] }],
        responses: { 200: { description: 'The broker link and the cells', ...json({ type: 'object', required: ['broker', 'cells'], properties: { broker: { type: 'object' }, cells: { type: 'array' } } }) }, 404: { description: 'No plant section', ...json(error) }, ...guarded },
      },
    },
    '/api/plant/events': {
      get: {
        summary: 'The same as /api/plant/cells as Server-Sent Events (event "cells"), on connect and on every change', security: [{ session: [] }],
        responses: { 200: { description: 'An event stream', content: { 'text/event-stream': { schema: { type: 'object', required: ['event', 'data'], properties: { event: { const: 'cells' }, data: { type: 'string', contentMediaType: 'application/json' } } } } } }, 404: { description: 'No plant section', ...json(error) }, ...guarded },
      },
    },
  },
});
