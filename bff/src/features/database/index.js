// Database update (feature 10): replace the cell's listed database files from a USB drive on the robot PC or
// from an upload, with content checks, atomic writes and backups. HTTP only: no ROS names.
import { defineFeature, featureSchema } from '../../core/features/feature.js';
import { DatabaseFiles, resolveUsbRoots } from './database-files.js';
import { databaseRoutes, databaseOpenApiPaths } from './routes.js';

export { DatabaseFiles, DatabaseError, resolveUsbRoots, isSafeName, isSafeRelPath, DEFAULT_USB_ROOTS, DEFAULT_MAX_UPLOAD_BYTES } from './database-files.js';
export { databaseRoutes, databaseOpenApiPaths } from './routes.js';
export { checkContent, checkCsv, ContentError } from './content-check.js';

export default defineFeature({
  id: 'database',
  title: 'Database',
  schema: featureSchema('database'),
  // Names only: directories and USB roots stay on the robot PC.
  view: (section) => ({ files: section.files, max_upload_bytes: section.max_upload_bytes }),
  routes: ({ cell, env, audit, guard, log }) => databaseRoutes({
    service: new DatabaseFiles({ cell: { database: cell.database }, dataDir: env.dataDir, usbRoots: resolveUsbRoots(env.usbRoots, { database: cell.database }), audit }),
    guard, log,
  }),
  openapi: databaseOpenApiPaths,
});
