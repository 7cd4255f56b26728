// The engineer's tools and the flight recorder on the ros_control arm, from its cell file alone: the arm's driver
// topic (/iiwa/joint_states, named in the cell file) is listed with its type and publisher and measured at the
// simulated driver's rate; the driver's node is alive; a recording saved by hand holds that topic's messages at
// that rate (read back with the mcap library).
import fs from 'node:fs';
import yaml from 'js-yaml';
import { test, expect } from '@playwright/test';
import { loginAs, goToPage } from '../lib/app.js';
import { MCAP_MAGIC, listed, newRecording } from '../lib/recorder.js';
import { rosCli } from '../lib/ros.js';

const cell = /** @type {any} */ (yaml.load(fs.readFileSync(String(process.env.E2E_CELL_CONFIG), 'utf8')));
const JOINT_STATES = cell.manual.groups[0].ros_control.joint_states;
const RATE_HZ = cell.simulation.arms[0].rate_hz;
const DRIVER = cell.modules.find((/** @type {any} */ m) => /driver/i.test(m.name)).nodes[0];

test('Inspect: the arm\'s joint states listed with type and driver, measured at the driver\'s rate within 10 %; the driver alive', async ({ page }) => {
  test.slow();
  await loginAs(page, 'admin');
  await goToPage(page, 'Inspect');
  await page.getByRole('tab', { name: 'Topics' }).click();
  await page.getByLabel('Filter topics').fill(JOINT_STATES);
  const row = page.locator(`[data-testid="topic-row"][data-topic="${JOINT_STATES}"]`);
  await expect(row).toHaveCount(1, { timeout: 20_000 });
  await expect(row).toContainText('sensor_msgs/JointState');
  await page.getByRole('button', { name: `Topic ${JOINT_STATES}`, exact: true }).click();
  const detail = page.getByTestId('topic-detail');
  await expect(detail).toContainText(DRIVER);
  const rate = detail.getByTestId('topic-rate');
  await expect.poll(async () => parseFloat((await rate.textContent()) || ''), { timeout: 20_000 }).toBeGreaterThan(RATE_HZ * 0.9);
  expect(parseFloat((await rate.textContent()) || ''), 'the measured rate').toBeLessThan(RATE_HZ * 1.1);

  await page.getByRole('tab', { name: 'Nodes' }).click();
  await page.getByLabel('Filter nodes').fill(DRIVER);
  const nodeRow = page.locator(`[data-testid="node-row"][data-node="${DRIVER}"]`);
  await expect(nodeRow).toHaveAttribute('data-alive', 'true', { timeout: 15_000 });
  await nodeRow.getByRole('button', { name: `Node ${DRIVER}` }).click();
  await expect(nodeRow).toContainText(JOINT_STATES);
});

test('Recordings: one saved by hand holds the arm\'s joint states as sensor_msgs/JointState', async ({ page }) => {
  test.slow();
  await loginAs(page, 'operator');
  await goToPage(page, 'Recordings');
  const before = await listed(page);
  await page.getByRole('button', { name: 'Save recording' }).click();
  const row = await newRecording(page, before);
  const name = /** @type {string} */ (await row.getAttribute('data-name'));
  await expect(row).toContainText('saved by hand');
  const [download] = await Promise.all([
    page.waitForEvent('download'),
    row.getByRole('link', { name: /^Download recording of / }).click(),
  ]);
  const bytes = fs.readFileSync(/** @type {string} */ (await download.path()));
  expect(bytes.subarray(0, 8).equals(MCAP_MAGIC)).toBe(true);
  expect(bytes.includes(Buffer.from(JOINT_STATES)), `${JOINT_STATES} is a channel of the file`).toBe(true);
  expect(bytes.includes(Buffer.from('sensor_msgs/JointState'))).toBe(true);
  // The recorder's description of it names the topic and its type.
  const described = await (await page.request.get(`/api/recorder/recordings/${name}`)).json();
  expect(described.topics.find((/** @type {any} */ t) => t.topic === JOINT_STATES)?.type).toBe('sensor_msgs/JointState');
  // Read back with the mcap library (as a recording's reader would): none lost, i.e. the header's sequence numbers
  // (rospy numbers each message the driver publishes: the first field of its ROS 1 bytes) follow on without a gap;
  // and the driver's stream, not a trickle (the driver skips ticks when its host is starved; the recorder must keep
  // what it sent).
  const py = 'import sys, struct; from mcap.reader import make_reader; '
    + 'm = list(make_reader(open(sys.argv[1], "rb")).iter_messages(topics=[sys.argv[2]])); '
    + 's = [struct.unpack_from("<I", x.data)[0] for _, _, x in m]; '
    + 'print(len(m), (m[-1][2].log_time - m[0][2].log_time) / 1e9 if len(m) > 1 else 0, '
    + 'sum(1 for a, b in zip(s, s[1:]) if b != a + 1))';
  const { stdout } = await rosCli(`python -c '${py}' '${await download.path()}' '${JOINT_STATES}'`);
  const [count, span, gaps] = stdout.trim().split(/\s+/).map(Number);
  expect(span, 'seconds of joint states in the file').toBeGreaterThan(5);
  expect(gaps, 'gaps in the joint states\' sequence numbers').toBe(0);
  expect(count / span, 'joint states a second in the file').toBeGreaterThan(RATE_HZ / 2);
});
