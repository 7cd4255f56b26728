#!/usr/bin/env node
// npm run audit -- verify [--data-dir DIR]: checks the audit log's hash chain (bff/src/core/audit/verify.js).
// Exit 0: intact (one summary line, which also lists the torn writes and lagging heads the BFF repaired at start);
// 1: altered, removed, inserted or torn entries (the first one is printed); 2: bad arguments or an unreadable data dir.
import fs from 'node:fs';
import path from 'node:path';
import { readEnv } from '../core/config/env.js';
import { readAuditDir, verifyAuditLog } from '../core/audit/verify.js';

const USAGE = `usage: npm run audit -- verify [--data-dir DIR]
       npm run audit -- help
verify: checks the hash chain of DIR/audit.log, its rotated files and DIR/audit.head.
DIR defaults to DATA_DIR (default .data in the repository).
Exit 0: intact (repairs the BFF made at start after a crash are listed); 1: entries altered, removed, inserted or
torn (the first is printed); 2: usage.`;

class UsageError extends Error {}

/** @param {string[]} argv @returns {number} the exit code */
function main(argv) {
  const [cmd, ...rest] = argv;
  if (cmd === 'help' || cmd === '--help' || cmd === '-h') { console.log(USAGE); return 0; }
  if (cmd !== 'verify') throw new UsageError(cmd ? `unknown command "${cmd}"\n${USAGE}` : USAGE);
  let dir;
  for (let i = 0; i < rest.length; i++) {
    const a = rest[i];
    if (a === '--data-dir' && rest[i + 1] !== undefined && !rest[i + 1].startsWith('--')) dir = rest[++i];
    else if (a.startsWith('--data-dir=') && a.length > '--data-dir='.length) dir = a.slice('--data-dir='.length);
    else if (a === '--help' || a === '-h') { console.log(USAGE); return 0; }
    else throw new UsageError(`${a === '--data-dir' ? '--data-dir needs a directory' : `unknown argument "${a}"`}\n${USAGE}`);
  }
  dir = path.resolve(dir ?? readEnv().dataDir);
  if (!fs.existsSync(dir) || !fs.statSync(dir).isDirectory()) throw new UsageError(`${dir}: no such directory`);
  const verdict = verifyAuditLog(readAuditDir(dir));
  if (verdict.ok) {
    console.log(verdict.summary);
    return 0;
  }
  console.log(`${verdict.summary}\n(in ${dir})`);
  return 1;
}

try {
  process.exitCode = main(process.argv.slice(2));
} catch (e) {
  console.error(e instanceof UsageError ? e.message : e.stack || String(e));
  process.exitCode = 2;
}
