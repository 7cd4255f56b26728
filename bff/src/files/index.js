// Database files of the cell: replace from a USB drive or an upload, with backups and restore.
export { DatabaseFiles, DatabaseError, resolveUsbRoots, isSafeName, isSafeRelPath, DEFAULT_USB_ROOTS, DEFAULT_MAX_UPLOAD_BYTES } from './database-files.js';
export { databaseRoutes, databaseOpenApiPaths } from './routes.js';
export { checkContent, checkCsv, ContentError } from './content-check.js';
