#!/usr/bin/env node
// npm run check-config -- <cell.yaml>: validates a cell file; exit 0 when valid, 2 with the bad fields otherwise.
//
// Two layers, both "invalid" with exit 2:
// 1. the BFF's own check (bff/src/core/config/cell.js: JSON Schema, then cross-references), as at start;
// 2. then the ROS nodes' and the simulator's own parsers (python -m cell_nodes.check), which refuse more than a
//    schema can say: a process step naming a configuration the driver lacks, a parameter default outside its range,
//    duplicate module names, an unknown sim camera view... Such a file would make a node exit at start and respawn.
//
// Layer 2 needs the project's Python venv (.venv, made by `bash scripts/bootstrap.sh`, i.e. by `npm start` or
// `npm test`). `npm run check-config` itself only runs `bootstrap.sh npm`, which installs the npm packages and not
// the venv; on a checkout where the venv was never made, the schema check alone decides (exit 0 when it passes) and
// a warning says the node-level checks were skipped: refusing every file there would make the command useless
// before the first `npm start`, and that start builds the venv. The check needs PyYAML and the sources only, not
// the catkin workspace (no message classes, no ROS master): the sources go on PYTHONPATH directly.
// Exit 3: the venv is there but the checker could not run (a broken venv, or a bug in the checker).
import path from 'node:path';
import fs from 'node:fs';
import { spawnSync } from 'node:child_process';
import { loadCell, CellConfigError } from '../core/config/cell.js';
import { FEATURES } from '../features/index.js';
import { readEnv, REPO_ROOT } from '../core/config/env.js';

const PYTHON = path.join(REPO_ROOT, '.venv/bin/python');
const PYTHON_PATH = [REPO_ROOT, path.join(REPO_ROOT, 'ros_backend/src/cell_nodes/src')];

/**
 * Run the nodes' parsers over the file.
 * @param {string} file
 * @returns {{ skipped: boolean, status: number | null, lines: string[], stderr: string }}
 */
function nodeChecks(file) {
  if (!fs.existsSync(PYTHON)) return { skipped: true, status: null, lines: [], stderr: '' };
  const env = { ...process.env, PYTHONPATH: [...PYTHON_PATH, process.env.PYTHONPATH].filter(Boolean).join(path.delimiter) };
  const r = spawnSync(PYTHON, ['-m', 'cell_nodes.check', path.resolve(file)], { cwd: REPO_ROOT, env, encoding: 'utf8', timeout: 60_000 });
  const lines = (r.stdout || '').split('\n').filter((l) => l.trim());
  return { skipped: false, status: r.error ? null : r.status, lines, stderr: r.error ? String(r.error) : r.stderr || '' };
}

const file = process.argv[2] || readEnv().cellConfig;
let cell;
try {
  cell = loadCell(file, FEATURES);
} catch (e) {
  console.error(e instanceof CellConfigError ? e.message : String(e));
  process.exit(2);
}

const checked = nodeChecks(file);
if (checked.skipped) {
  console.error('warning: node-level checks skipped: run npm start or bash scripts/bootstrap.sh once');
} else if ((checked.status === 1 || checked.status === 2) && checked.lines.length) {
  const problems = checked.lines.filter((l) => !l.startsWith('warning: '));
  console.error(`${file}: invalid cell file (the ROS nodes or the simulator refuse it)\n${problems.map((p) => `  - ${p}`).join('\n')}`);
  for (const w of checked.lines.filter((l) => l.startsWith('warning: '))) console.error(`  ${w}`);
  process.exit(2);
} else if (checked.status !== 0) {
  const why = checked.stderr.split('\n').filter((l) => l.trim()).slice(-3).join('\n  ');
  console.error(`${file}: the node-level checks could not run (python -m cell_nodes.check, exit ${checked.status}); `
    + `a broken .venv? run bash scripts/bootstrap.sh\n  ${why}`);
  process.exit(3);
} else {
  for (const w of checked.lines) console.error(w);
}
console.log(`${file}: valid (cell "${cell.cell.id}", roles: ${Object.keys(cell.roles).join(', ')})`);
