// The Inspect page's Topics and Nodes, as an engineer with a tablet uses them instead of `rostopic hz/echo` and
// `rosnode info`: a topic an engineer publishes at 20 Hz from a terminal is listed with its type and publisher, its
// rate reads 20 Hz within 10 %, its last message shows (admins: the demo cell's echo_roles); its node is listed
// alive, then "not responding" once killed. An operator reads none of it through /ros.
import { test, expect } from '@playwright/test';
import { loginAs, goToPage, sessionCookie, rosSocket } from '../lib/app.js';
import { rosCliRunning } from '../lib/ros.js';

const RATE_HZ = 20;

test('a topic published at 20 Hz: listed with type and publisher, rate within 10 %, last message; its node alive, then not responding', async ({ page }) => {
  test.slow();
  const tag = `e2e_${test.info().project.name}_${Date.now()}`;
  const topic = `/${tag}/count`;
  const node = `/${tag}_pub`;
  const pub = rosCliRunning(`rostopic pub -r ${RATE_HZ} ${topic} std_msgs/String "data: '${tag} hello'" __name:=${node.slice(1)}`);
  try {
    await loginAs(page, 'admin');
    await goToPage(page, 'Inspect');
    await page.getByRole('tab', { name: 'Topics' }).click();
    await page.getByLabel('Filter topics').fill(tag);
    const row = page.locator(`[data-testid="topic-row"][data-topic="${topic}"]`);
    // The list refreshes every 5 s; rostopic pub registers within a second or two.
    await expect(row).toHaveCount(1, { timeout: 20_000 });
    await expect(row).toContainText('std_msgs/String');
    await page.getByRole('button', { name: `Topic ${topic}`, exact: true }).click();
    const detail = page.getByTestId('topic-detail');
    await expect(detail).toContainText(node);
    const rate = detail.getByTestId('topic-rate');
    // The window fills over 10 s; from about 3 s on the measured rate settles.
    await expect.poll(async () => parseFloat((await rate.textContent()) || ''), { timeout: 20_000 })
      .toBeGreaterThan(RATE_HZ * 0.9);
    const hz = parseFloat((await rate.textContent()) || '');
    expect(hz, 'the measured rate').toBeGreaterThan(RATE_HZ * 0.9);
    expect(hz, 'the measured rate').toBeLessThan(RATE_HZ * 1.1);
    await expect(detail.getByTestId('topic-bandwidth')).toContainText('/s');

    await detail.getByRole('button', { name: 'Show last message' }).click();
    await expect(detail.getByTestId('topic-message')).toContainText(`${tag} hello`, { timeout: 10_000 });

    await page.getByRole('tab', { name: 'Nodes' }).click();
    await page.getByLabel('Filter nodes').fill(tag);
    const nodeRow = page.locator(`[data-testid="node-row"][data-node="${node}"]`);
    await expect(nodeRow).toHaveAttribute('data-alive', 'true', { timeout: 15_000 });
    await expect(nodeRow).toContainText('alive');
    await nodeRow.getByRole('button', { name: `Node ${node}` }).click();
    await expect(nodeRow).toContainText(topic);
    // Killed without unregistering: the master still lists it, it no longer answers.
    pub.kill('SIGKILL');
    await expect(nodeRow).toHaveAttribute('data-alive', 'false', { timeout: 15_000 });
    await expect(nodeRow).toContainText('not responding');
  } finally {
    pub.kill('SIGKILL');
  }
});

test('an operator cannot list the graph, measure a topic or read a message through /ros', async ({ page, context, baseURL }) => {
  await loginAs(page, 'operator');
  const ros = await rosSocket(/** @type {string} */ (baseURL), await sessionCookie(context));
  try {
    for (const [i, service] of ['/cell/inspect/graph', '/cell/inspect/topic_stats', '/cell/inspect/echo'].entries()) {
      ros.send({ op: 'call_service', id: `g${i}`, service, args: { topic: '/joint_states' } });
      const answer = await ros.waitFor((m) => m.op === 'service_response' && m.id === `g${i}`);
      expect(answer.result, service).toBe(false);
      expect(String(answer.values), service).toMatch(/permission denied/);
    }
  } finally {
    ros.ws.close();
  }
});
