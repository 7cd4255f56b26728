// Helpers for specs that run the process: which pose-table entry the running cycle uses.
import { expect } from '@playwright/test';

/**
 * The 0-based pose-table entry of the cycle the Process page shows as running ("Cycle N of M"): a table of
 * `length` entries repeats, so cycle N uses entry (N - 1) mod length (as the process node's table_index).
 * @param {import('@playwright/test').Page} page @param {number} length
 */
export async function cycleEntry(page, length) {
  const cycle = page.getByTestId('process-cycle');
  await expect(cycle).toHaveText(/^Cycle \d+/);
  const n = Number(/^Cycle (\d+)/.exec(String(await cycle.textContent()))?.[1]);
  return (n - 1) % length;
}
