// Prints, for every failed attempt, the page's accessibility snapshot that Playwright saved (error-context.md) and
// its last steps: CI keeps only the console output, not test-results/.
import { readFileSync } from 'node:fs';

/** @implements {import('@playwright/test/reporter').Reporter} */
export default class FailureContextReporter {
  /** @param {import('@playwright/test/reporter').TestCase} test @param {import('@playwright/test/reporter').TestResult} result */
  onTestEnd(test, result) {
    if (result.status === 'passed' || result.status === 'skipped') return;
    const lines = [`\n--- ${result.status} (attempt ${result.retry + 1}): ${test.titlePath().filter(Boolean).join(' › ')}`];
    for (const step of result.steps) {
      if (step.error || step.duration < 0) lines.push(`step: ${step.title}${step.error ? ` (error: ${step.error.message?.split('\n')[0]})` : ''}`);
    }
    lines.push(`last steps: ${result.steps.slice(-4).map((s) => `${s.title} (${s.duration} ms)`).join('; ')}`);
    for (const a of result.attachments) {
      if (a.name !== 'error-context' || !a.path) continue;
      try {
        const text = readFileSync(a.path, 'utf8');
        const snapshot = text.indexOf('# Page snapshot');
        if (snapshot >= 0) lines.push(text.slice(snapshot, text.indexOf('\n# ', snapshot + 1) >>> 0).slice(0, 6000));
      } catch (e) {
        lines.push(`(error context unreadable: ${/** @type {Error} */ (e).message})`);
      }
    }
    process.stdout.write(`${lines.join('\n')}\n---\n`);
  }
}
