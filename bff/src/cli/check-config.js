#!/usr/bin/env node
// npm run check-config -- <cell.yaml>: validates a cell file; exit 0 when valid, 2 with the bad fields otherwise.
import { loadCell, CellConfigError } from '../core/config/cell.js';
import { FEATURES } from '../features/index.js';
import { readEnv } from '../core/config/env.js';

const file = process.argv[2] || readEnv().cellConfig;
try {
  const cell = loadCell(file, FEATURES);
  console.log(`${file}: valid (cell "${cell.cell.id}", roles: ${Object.keys(cell.roles).join(', ')})`);
} catch (e) {
  console.error(e instanceof CellConfigError ? e.message : String(e));
  process.exit(2);
}
