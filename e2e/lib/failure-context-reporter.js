// Prints, for every failed test, its last steps, the page's accessibility snapshot that Playwright saved
// (error-context.md), what the stack logged while the test ran and the control lease's audit entries of that time:
// CI keeps only the console output, not test-results/. Playwright writes error-context.md in the test's output
// folder, and may attach it only after the test's end is reported: so the snapshot is read from that folder (found
// from the result's attachments, e.g. its screenshot), now or at the end of the run. A matcher that failed on a
// locator puts its own snapshot of the page under the error (a yaml block), and then there is no page snapshot.
import { existsSync, readFileSync, readdirSync, statSync, openSync, readSync, closeSync } from 'node:fs';
import path from 'node:path';

/** @typedef {import('@playwright/test/reporter').TestCase} TestCase */
/** @typedef {import('@playwright/test/reporter').TestResult} TestResult */

/** @param {TestResult} result @returns {string | null} the error-context.md of the result, if known */
function contextFile(result) {
  const named = result.attachments.find((a) => a.name === 'error-context' && a.path);
  if (named?.path) return named.path;
  const any = result.attachments.find((a) => a.path);
  return any?.path ? path.join(path.dirname(any.path), 'error-context.md') : null;
}

/** @param {string} file @returns {string | null} the page snapshot part of an error-context.md */
function snapshotOf(file) {
  try {
    const text = readFileSync(file, 'utf8');
    const at = text.indexOf('# Page snapshot');
    if (at >= 0) {
      const end = text.indexOf('\n# ', at + 1);
      return text.slice(at, end < 0 ? undefined : end).slice(0, 6000);
    }
    const yamlAt = text.indexOf('```yaml');
    if (yamlAt < 0) return '(no page snapshot in the error context)';
    const yamlEnd = text.indexOf('```', yamlAt + 7);
    return `# The page, as the failed matcher saw it\n${text.slice(yamlAt, yamlEnd < 0 ? undefined : yamlEnd + 3).slice(0, 6000)}`;
  } catch (e) {
    return `(error context unreadable: ${/** @type {Error} */ (e).message})`;
  }
}

/** @param {string} file @returns {number} its size now (0: none) */
const sizeOf = (file) => {
  try {
    return statSync(file).size;
  } catch {
    return 0;
  }
};

/** @param {string} file @param {number} from @returns {string} what was appended to the file since `from` */
function readFrom(file, from) {
  const size = sizeOf(file);
  if (size <= from) return '';
  const buf = Buffer.alloc(size - from);
  const fd = openSync(file, 'r');
  try {
    readSync(fd, buf, 0, buf.length, from);
  } finally {
    closeSync(fd);
  }
  return buf.toString('utf8');
}

/** @implements {import('@playwright/test/reporter').Reporter} */
/** An expect error on one line, with what was expected and received (colour codes removed). @param {string | undefined} m */
const errorText = (m) => (m ?? '').replace(/\x1b\[[0-9;]*m/g, '').split('\n').map((l) => l.trim()).filter(Boolean).slice(0, 4).join(' | ');

export default class FailureContextReporter {
  /** Failed tests whose error context was not written yet when their end was reported. @type {{title: string, file: string}[]} */
  pending = [];
  /** Where the stack's log, audit log and ROS node logs stood when each test began. @type {Map<string, {log: number, audit: number, nodes: Map<string, number>}>} */
  marks = new Map();

  /** The stack's log and audit log (the stack is started by the global setup, which sets E2E_DATA_DIR). */
  files() {
    const dir = process.env.E2E_DATA_DIR;
    return dir ? { log: path.join(dir, 'stack.log'), audit: path.join(dir, 'audit.log') } : null;
  }

  /**
   * The ROS nodes' own log files (`output="log"` in the launch files: what a node logs through Python's logging,
   * e.g. the manual driver's jog decisions, and rospy's topic connections), not in the stack log.
   * @returns {string[]}
   */
  nodeLogs() {
    const dir = process.env.E2E_DATA_DIR && path.join(process.env.E2E_DATA_DIR, 'ros', 'log');
    if (!dir || !existsSync(dir)) return [];
    const runs = readdirSync(dir, { withFileTypes: true }).filter((d) => d.isDirectory()).map((d) => path.join(dir, d.name));
    return runs.flatMap((run) => readdirSync(run).filter((f) => /^[a-z_]+-\d+\.log$/.test(f) && !f.startsWith('roslaunch-'))
      .map((f) => path.join(run, f)));
  }

  /** @param {TestCase} test */
  onTestBegin(test) {
    const f = this.files();
    if (f) this.marks.set(test.id, { log: sizeOf(f.log), audit: sizeOf(f.audit), nodes: new Map(this.nodeLogs().map((n) => [n, sizeOf(n)])) });
  }

  /** What the stack logged during the test (the last lines) and its control lease's audit entries. @param {TestCase} test */
  stackContext(test) {
    const f = this.files();
    const mark = this.marks.get(test.id);
    this.marks.delete(test.id);
    if (!f || !mark) return [];
    const logged = readFrom(f.log, mark.log).trimEnd().split('\n').filter(Boolean);
    const control = readFrom(f.audit, mark.audit).split('\n').filter((l) => l.includes('"op":"control.')).map((l) => {
      try {
        const e = JSON.parse(l);
        return `${e.time} ${e.op} ${e.target ?? ''} by ${e.user ?? '-'}${e.detail ? ` (${e.detail})` : ''}`;
      } catch {
        return l;
      }
    });
    // A node log started during the test (a respawned node) is read from its beginning.
    const nodeLines = this.nodeLogs().flatMap((n) => {
      const lines = readFrom(n, mark.nodes.get(n) ?? 0).split('\n').filter(Boolean);
      const node = path.basename(n, '.log');
      return lines.length ? [`${node} (last 20 of ${lines.length} lines):`, ...lines.slice(-20).map((l) => `  ${l}`)] : [];
    });
    return [
      `stack log during the test (last 40 of ${logged.length} lines):`, ...logged.slice(-40).map((l) => `  ${l}`),
      'ROS node logs during the test:', ...nodeLines.map((l) => `  ${l}`),
      `control lease audit entries during the test (${control.length}):`, ...control.map((l) => `  ${l}`),
    ];
  }

  /** @param {TestCase} test @param {TestResult} result */
  onTestEnd(test, result) {
    if (result.status === 'passed' || result.status === 'skipped') {
      this.marks.delete(test.id);
      return;
    }
    const title = test.titlePath().filter(Boolean).join(' › ');
    const lines = [`\n--- ${result.status} (attempt ${result.retry + 1}): ${title}`];
    for (const step of result.steps) {
      if (step.error || step.duration < 0) lines.push(`step: ${step.title}${step.error ? ` (error: ${errorText(step.error.message)})` : ''}`);
    }
    lines.push(`last steps: ${result.steps.slice(-4).map((s) => `${s.title} (${s.duration} ms)`).join('; ')}`);
    const file = contextFile(result);
    if (file && existsSync(file)) lines.push(/** @type {string} */ (snapshotOf(file)));
    else if (file) this.pending.push({ title, file });
    else lines.push('(no output folder known for this test: no page snapshot)');
    lines.push(...this.stackContext(test));
    process.stdout.write(`${lines.join('\n')}\n---\n`);
  }

  onEnd() {
    for (const { title, file } of this.pending) {
      process.stdout.write(`\n--- page snapshot of the failed test: ${title}\n${existsSync(file) ? snapshotOf(file) : `(no ${file})`}\n---\n`);
    }
  }
}
