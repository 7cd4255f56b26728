// The BFF is the only door: an operator's forbidden rosbridge ops through /ros are refused with rosbridge
// errors and never reach ROS; the admin pages' APIs are refused too. On every profile.
import { test, expect } from '@playwright/test';
import { loginAs, sessionCookie, rosSocket } from '../lib/app.js';
import { rosCli, publishMode } from '../lib/ros.js';


test('an operator cannot publish, advertise, call forbidden services or subscribe outside the grant', async ({ page, context, baseURL }) => {
  await publishMode('idle');
  await loginAs(page, 'operator');
  const ros = await rosSocket(baseURL, await sessionCookie(context));

  ros.send({ op: 'publish', id: 'p1', topic: '/cell/mode', msg: { mode: 'running', source: 'operator' } });
  expect((await ros.waitFor((m) => m.op === 'status' && m.id === 'p1')).level).toBe('error');

  ros.send({ op: 'call_service', id: 'c1', service: '/cell/set_mode', args: { mode: 'running', source: 'operator' } });
  const resp = await ros.waitFor((m) => m.op === 'service_response' && m.id === 'c1');
  expect(resp.result).toBe(false);
  expect(String(resp.values)).toContain('permission denied');

  ros.send({ op: 'advertise', id: 'a1', topic: '/evil_topic', type: 'std_msgs/String' });
  await ros.waitFor((m) => m.op === 'status' && m.id === 'a1' && m.level === 'error');
  ros.send({ op: 'subscribe', id: 's1', topic: '/rosout' });
  await ros.waitFor((m) => m.op === 'status' && m.id === 's1' && m.level === 'error');
  ros.send({ op: 'fragment', id: 'f1', data: '{"op":"publish"', num: 0, total: 2 });
  await ros.waitFor((m) => m.op === 'status' && m.id === 'f1' && m.level === 'error');

  // Allowed: the granted service and topic still work on the same socket.
  ros.send({ op: 'call_service', id: 'c2', service: '/cell/get_mode', args: {} });
  const ok = await ros.waitFor((m) => m.op === 'service_response' && m.id === 'c2');
  expect(ok.result).toBe(true);
  expect(ok.values.mode).toBe('idle');

  // Nothing reached ROS: the mode is unchanged and the topic was never advertised.
  const mode = await rosCli('rosservice call /cell/get_mode');
  expect(mode.stdout).toContain('mode: "idle"');
  const topics = await rosCli('rostopic list');
  expect(topics.stdout).not.toContain('/evil_topic');

  // rosapi answers list only what the role may use (the operator has no /rosapi grant at all).
  ros.send({ op: 'call_service', id: 'r1', service: '/rosapi/topics', args: {} });
  expect((await ros.waitFor((m) => m.op === 'service_response' && m.id === 'r1')).result).toBe(false);
  ros.ws.close();
});

test('an admin may do what the operator may not; rosapi lists everything for the admin', async ({ page, context, baseURL }) => {
  await loginAs(page, 'admin');
  const ros = await rosSocket(baseURL, await sessionCookie(context));
  ros.send({ op: 'call_service', id: 'c1', service: '/cell/set_mode', args: { mode: 'manual', source: 'admin' } });
  expect((await ros.waitFor((m) => m.op === 'service_response' && m.id === 'c1')).values.success).toBe(true);
  ros.send({ op: 'call_service', id: 'r1', service: '/rosapi/topics', args: {} });
  const topics = await ros.waitFor((m) => m.op === 'service_response' && m.id === 'r1');
  expect(topics.values.topics).toContain('/cell/mode');
  ros.ws.close();
  await publishMode('idle');
});

test('an operator cannot reach the admin pages or their APIs', async ({ page }) => {
  await loginAs(page, 'operator');
  for (const api of ['/api/system', '/api/audit']) expect((await page.request.get(api)).status(), api).toBe(403);
  await page.goto('/system');
  await expect(page.getByTestId('access-denied')).toBeVisible();
});
