// Automatic process (feature 5): start, stop, pause/resume, run one step; its state, status fields and log.
// Node: /cell/process/. Start, resume, step and an action goal move the robot (lease); stop, pause and cancel never wait for it.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

export default defineFeature({
  id: 'process',
  title: 'Process',
  schema: featureSchema('process'),
  view: (section) => ({ operations: section.operations || [], status_fields: section.status_fields || [] }),
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
