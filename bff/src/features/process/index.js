// Automatic process (feature 5): start, stop, pause/resume, run one operation, dry run; its state, status fields
// and log. Nodes: /cell/process/ (cell_nodes process). Start, resume, step and an action goal move the robot
// (lease); stop, pause and cancel never wait for it.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

/** @param {any} o @returns {string} */
const operationName = (o) => (typeof o === 'string' ? o : String(o?.name ?? ''));

export default defineFeature({
  id: 'process',
  title: 'Process',
  schema: featureSchema('process'),
  // The page needs the names (the node's state has them too, live) and the status panel; the steps stay on the PC.
  view: (section) => ({
    operations: (section.operations || []).map(operationName),
    // What the page shows for an operation, by name (a text per language), where the cell file gives one.
    titles: Object.fromEntries((section.operations || []).filter((o) => o?.title).map((o) => [o.name, o.title])),
    // The steps' own texts and notes given per language: the node says them in English, the page in the user's.
    step_texts: (section.operations || []).flatMap((o) => (Array.isArray(o?.steps) ? o.steps : []))
      .flatMap((s) => [s?.text, s?.note]).filter((t) => t && typeof t === 'object'),
    status_fields: section.status_fields || [],
    start_configuration: section.start_configuration ?? null,
  }),
  reads: (section) => ({
    subscribe: ['/cell/process/state', '/cell/process/log', ...(section.status_fields || []).map((f) => f.topic),
      ...(section.action ? [`${section.action}/status`, `${section.action}/feedback`, `${section.action}/result`] : [])],
  }),
  commands: () => ({ call_service: ['/cell/process/set_dry_run'] }),
  motion: (section) => ({
    call_service: ['/cell/process/start', '/cell/process/resume', '/cell/process/step'],
    publish: section.action ? [`${section.action}/goal`] : [],
  }),
  stop: (section) => ({
    call_service: ['/cell/process/stop', '/cell/process/pause'],
    publish: section.action ? [`${section.action}/cancel`] : [],
  }),
});
