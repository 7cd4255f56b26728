// Recorder (the flight recorder): the recorder node keeps the last seconds of the cell's topics and saves them
// around every error alarm as an MCAP file with a JSON description beside it. The page lists them (when, why,
// size), downloads them, draws a recording's timeline, saves one by hand and, for the roles the cell file names,
// deletes them. Node: /cell/recorder/ (state, save).
import { defineFeature, featureSchema } from '../../core/features/feature.js';
import { Recordings, recordingsDir } from './recordings.js';
import { recorderRoutes, recorderOpenApiPaths } from './routes.js';

export { Recordings, RecordingError, RECORDING_NAME, recordingsDir } from './recordings.js';
export { recorderRoutes, recorderOpenApiPaths } from './routes.js';

/** @param {any} section @param {string} role */
const mayDelete = (section, role) => Array.isArray(section?.delete_roles) && section.delete_roles.includes(role);

export default defineFeature({
  id: 'recorder',
  title: 'Recordings',
  schema: featureSchema('recorder'),
  check: (section, cell) => (section.delete_roles || []).flatMap((r, i) => (cell.roles?.[r] ? [] : [`recorder.delete_roles[${i}]: no role ${JSON.stringify(r)} in roles`])),
  view: (section, role) => ({ before_s: section.before_s ?? 120, after_s: section.after_s ?? 10, can_delete: mayDelete(section, role) }),
  reads: () => ({ subscribe: ['/cell/recorder/state'] }),
  commands: () => ({ call_service: ['/cell/recorder/save'] }),
  routes: ({ section, env, audit, guard, log }) => recorderRoutes({
    recordings: new Recordings({ dir: recordingsDir(section, env) }), canDelete: (role) => mayDelete(section, role), guard, audit, log,
  }),
  openapi: recorderOpenApiPaths,
});
