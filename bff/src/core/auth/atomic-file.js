// Write a file so that readers see the old or the new content, never a torn one.
import fs from 'node:fs';
import path from 'node:path';

/** @param {string} file @param {string|Buffer} data @param {number} [mode] */
export function writeFileAtomic(file, data, mode = 0o600) {
  const dir = path.dirname(file);
  fs.mkdirSync(dir, { recursive: true });
  const tmp = path.join(dir, `.${path.basename(file)}.${process.pid}.${Date.now()}.tmp`);
  const fd = fs.openSync(tmp, 'wx', mode);
  try {
    fs.writeSync(fd, Buffer.isBuffer(data) ? data : Buffer.from(data, 'utf8'));
    fs.fsyncSync(fd);
  } finally {
    fs.closeSync(fd);
  }
  fs.renameSync(tmp, file);
  try {
    const dfd = fs.openSync(dir, 'r');
    fs.fsyncSync(dfd);
    fs.closeSync(dfd);
  } catch { /* directory fsync is best effort on some filesystems */ }
}
