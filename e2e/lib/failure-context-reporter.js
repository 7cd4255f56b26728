// Prints, for every failed test, its last steps and the page's accessibility snapshot that Playwright saved
// (error-context.md): CI keeps only the console output, not test-results/. Playwright writes error-context.md in the
// test's output folder, and may attach it only after the test's end is reported: so the snapshot is read from that
// folder (found from the result's attachments, e.g. its screenshot), now or at the end of the run.
import { existsSync, readFileSync } from 'node:fs';
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
    if (at < 0) return '(no page snapshot in the error context)';
    const end = text.indexOf('\n# ', at + 1);
    return text.slice(at, end < 0 ? undefined : end).slice(0, 6000);
  } catch (e) {
    return `(error context unreadable: ${/** @type {Error} */ (e).message})`;
  }
}

/** @implements {import('@playwright/test/reporter').Reporter} */
export default class FailureContextReporter {
  /** Failed tests whose error context was not written yet when their end was reported. @type {{title: string, file: string}[]} */
  pending = [];

  /** @param {TestCase} test @param {TestResult} result */
  onTestEnd(test, result) {
    if (result.status === 'passed' || result.status === 'skipped') return;
    const title = test.titlePath().filter(Boolean).join(' › ');
    const lines = [`\n--- ${result.status} (attempt ${result.retry + 1}): ${title}`];
    for (const step of result.steps) {
      if (step.error || step.duration < 0) lines.push(`step: ${step.title}${step.error ? ` (error: ${step.error.message?.split('\n')[0]})` : ''}`);
    }
    lines.push(`last steps: ${result.steps.slice(-4).map((s) => `${s.title} (${s.duration} ms)`).join('; ')}`);
    const file = contextFile(result);
    if (file && existsSync(file)) lines.push(/** @type {string} */ (snapshotOf(file)));
    else if (file) this.pending.push({ title, file });
    else lines.push('(no output folder known for this test: no page snapshot)');
    process.stdout.write(`${lines.join('\n')}\n---\n`);
  }

  onEnd() {
    for (const { title, file } of this.pending) {
      process.stdout.write(`\n--- page snapshot of the failed test: ${title}\n${existsSync(file) ? snapshotOf(file) : `(no ${file})`}\n---\n`);
    }
  }
}
