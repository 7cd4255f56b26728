// Schemathesis (PyPI, installed into .venv from requirements.txt) against a live BFF with an admin session: every
// operation of /api/openapi.json with generated valid and invalid requests (path parameters, query strings, JSON and
// multipart bodies, undeclared methods, wrong content types), a fixed seed and a bounded number of examples.
// It must find no server error and no status, content type, header or body the document does not declare.
// ROS is not running here: /api/health says so (still a 200), and no HTTP route needs ROS.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { REPO_ROOT } from '../../src/core/config/env.js';
import { startBff, login, tempDir } from '../helpers.js';

const ST = path.join(REPO_ROOT, '.venv', 'bin', 'schemathesis');
const SEED = 20261123;
const MAX_EXAMPLES = 15; // per operation and phase: ~750 requests, about a minute on 2 busy cores (the suite's time: CI)
const CHECKS = [
  'not_a_server_error', 'status_code_conformance', 'content_type_conformance', 'response_schema_conformance',
  'response_headers_conformance', 'unsupported_method', 'allow_header_conformance', 'negative_data_rejection',
  'missing_required_header', 'ignored_auth',
  // Not positive_data_acceptance: a schema-valid upload can still carry the wrong file extension (415) and a
  // schema-valid backup name another file's prefix (400); the document says so, JSON Schema cannot express it.
];

let t;
let token;
const serverLog = [];
before(async () => {
  // A USB root with a drive and files, so the database routes have something to list and replace.
  const usb = tempDir('usb-root-');
  fs.mkdirSync(path.join(usb, 'STICK', 'export'), { recursive: true });
  fs.writeFileSync(path.join(usb, 'STICK', 'parts.csv'), 'id,name\n1,from the stick\n');
  fs.writeFileSync(path.join(usb, 'STICK', 'export', 'fixtures.yaml'), 'fixtures:\n  - id: F1\n');
  fs.writeFileSync(path.join(usb, 'STICK', 'notes.txt'), 'not a database file\n');
  t = await startBff({ USB_ROOTS: usb }, { log: (m) => serverLog.push(m) });
  const { res, cookie } = await login(t.base, 'admin', t.passwords.admin);
  assert.equal(res.status, 200);
  token = cookie.replace(/^cell_session=/, '');
});
after(() => t?.stop());

test('schemathesis finds no server error and nothing undocumented', { timeout: 300_000 }, async (ctx) => {
  assert.ok(fs.existsSync(ST), `${ST} is missing: run scripts/bootstrap.sh venv (requirements.txt lists schemathesis)`);
  const work = tempDir('schemathesis-');
  // OpenAPI-aware auth: the session goes into the `cell_session` cookie of the document's security scheme, so
  // schemathesis knows it and can leave it out on purpose (401 expected) instead of a fixed Cookie header.
  const config = path.join(work, 'schemathesis.toml');
  // Real names half of the time (the cell's database files, the drive, files on it), generated ones otherwise:
  // random names mostly get 404, and the replace/restore logic behind them would go untested.
  const toml = (v) => JSON.stringify(v);
  const files = t.bff.cell.database.files;
  fs.writeFileSync(config, [
    '[auth.openapi.session]', 'api_key = "${CELL_SESSION}"',
    '[dictionaries.files]', `values = ${toml(files)}`,
    '[dictionaries.drives]', `values = ${toml(['0:STICK'])}`,
    '[dictionaries.paths]', `values = ${toml(['parts.csv', 'export/fixtures.yaml', 'export', 'notes.txt'])}`,
    '[parameters]',
    '"path.name" = { dictionary = "files", probability = 0.5 }',
    '"path.drive" = { dictionary = "drives", probability = 0.5 }',
    '"query.path" = { dictionary = "paths", probability = 0.5 }',
    '"body.drive" = { dictionary = "drives", probability = 0.5 }',
    '"body.path" = { dictionary = "paths", probability = 0.5 }',
    // Invalid requests may also be refused as too large: the body (413), or the request line and headers (431,
    // Node's 16 kB limit: a 4096-character path of emoji is 49 kB percent-encoded).
    '[checks.negative_data_rejection]', 'expected-statuses = [400, 401, 403, 404, 405, 406, 409, 413, 415, 422, 428, 429, 431, "5XX"]',
  ].join('\n') + '\n');
  const args = [
    '--config-file', config, '--no-color', 'run', `${t.base}/api/openapi.json`,
    '--checks', CHECKS.join(','),
    '--seed', String(SEED), '--max-examples', String(MAX_EXAMPLES), '--workers', '1',
    '--generation-database', 'none', '--request-timeout', '10',
    // Logging out would revoke the admin session in the middle of the run (every later request a 401).
    '--exclude-path', '/api/auth/logout',
  ];
  const started = Date.now();
  const { code, out } = await new Promise((resolve, reject) => {
    const child = spawn(ST, args, { cwd: work, env: { ...process.env, CELL_SESSION: token, NO_COLOR: '1', COLUMNS: '120' } });
    let text = '';
    child.stdout.on('data', (d) => (text += d));
    child.stderr.on('data', (d) => (text += d));
    const killer = setTimeout(() => child.kill('SIGTERM'), 280_000);
    child.on('error', reject);
    child.on('close', (c, signal) => { clearTimeout(killer); resolve({ code: signal ? `signal ${signal}` : c, out: text }); });
  });
  const summary = out.slice(out.lastIndexOf('SUMMARY') - 40);
  ctx.diagnostic(`schemathesis exited ${code} after ${((Date.now() - started) / 1000).toFixed(0)} s; ${(summary.match(/\d+ generated[^\n]*/) || ['?'])[0]}`);
  const errors = serverLog.filter((m) => /^error on |^database: /.test(m));
  assert.equal(code, 0, `schemathesis ${args.join(' ')}\n\n${out}\n\nBFF log:\n${errors.join('\n')}`);
  assert.deepEqual(errors, [], 'the BFF logged no internal error');
});
