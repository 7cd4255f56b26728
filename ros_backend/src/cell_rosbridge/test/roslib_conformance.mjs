// roslib 2.x (the browser app's client library) against our rosbridge server, run under Node.
// Usage: node roslib_conformance.mjs <port>. Prints "ok <check>" per check; exit 0 only if all pass.
// Expects the pytest driver to have published: latched /rc_mode (cell_msgs/OperationMode, mode "running")
// and latched /rc_array (std_msgs/Float64MultiArray, data [1.5, NaN, -2]).
import { Ros, Topic, Service, Param } from 'roslib';

const port = process.argv[2];
const failures = [];
const timer = setTimeout(() => { console.log('FAIL global timeout'); process.exit(2); }, 25000);

function step(name, fn, ms = 8000) {
  return new Promise((resolve, reject) => {
    const t = setTimeout(() => reject(new Error(`timeout in ${name}`)), ms);
    fn((v) => { clearTimeout(t); resolve(v); }, (e) => { clearTimeout(t); reject(new Error(`${name}: ${e}`)); });
  });
}
async function check(name, fn) {
  try { await fn(); console.log(`ok ${name}`); }
  catch (e) { failures.push(name); console.log(`FAIL ${name}: ${e.message}`); }
}
function assert(cond, what) { if (!cond) throw new Error(what); }

const ros = new Ros();
await step('connect', (ok, bad) => { ros.on('connection', ok); ros.on('error', bad); ros.connect(`ws://127.0.0.1:${port}`); });

await check('getTopics', () => step('getTopics', (ok, bad) => ros.getTopics((r) => {
  assert(r.topics.includes('/rc_mode'), `topics ${r.topics}`);
  assert(r.types[r.topics.indexOf('/rc_mode')] === 'cell_msgs/OperationMode', 'type of /rc_mode');
  ok();
}, bad)));

await check('latched OperationMode (json)', () => step('mode', (ok) => {
  const t = new Topic({ ros, name: '/rc_mode', messageType: 'cell_msgs/OperationMode' });
  t.subscribe((m) => { assert(m.mode === 'running' && m.stamp.secs === 5, JSON.stringify(m)); t.unsubscribe(); ok(); });
}));

await check('second subscriber of same topic also gets latched state', () => step('mode2', (ok) => {
  const a = new Topic({ ros, name: '/rc_mode', messageType: 'cell_msgs/OperationMode' });
  const b = new Topic({ ros, name: '/rc_mode', messageType: 'cell_msgs/OperationMode' });
  a.subscribe(() => {
    b.subscribe((m) => { assert(m.mode === 'running', 'b'); a.unsubscribe(); b.unsubscribe(); ok(); });
  });
}));

await check('cbor typed arrays, NaN preserved', () => step('cbor', (ok) => {
  const t = new Topic({ ros, name: '/rc_array', messageType: 'std_msgs/Float64MultiArray', compression: 'cbor' });
  t.subscribe((m) => {
    const d = Array.from(m.data);
    assert(d.length === 3 && d[0] === 1.5 && Number.isNaN(d[1]) && d[2] === -2, `data ${d}`);
    t.unsubscribe(); ok();
  });
}));

await check('json NaN arrives as null', () => step('json', (ok) => {
  const t = new Topic({ ros, name: '/rc_array', messageType: 'std_msgs/Float64MultiArray' });
  t.subscribe((m) => { assert(m.data[1] === null && m.data[0] === 1.5, JSON.stringify(m.data)); t.unsubscribe(); ok(); });
}));

await check('png compression decodes', () => step('png', (ok) => {
  const t = new Topic({ ros, name: '/rc_array', messageType: 'std_msgs/Float64MultiArray', compression: 'png' });
  t.subscribe((m) => { assert(m.data[0] === 1.5 && m.data[2] === -2, JSON.stringify(m.data)); t.unsubscribe(); ok(); });
}));

await check('advertise + publish + subscribe roundtrip', () => step('echo', (ok) => {
  const sub = new Topic({ ros, name: '/rc_echo', messageType: 'std_msgs/String' });
  const pub = new Topic({ ros, name: '/rc_echo', messageType: 'std_msgs/String' });
  let sent = 0;
  sub.subscribe((m) => { assert(m.data === 'hi', m.data); clearInterval(iv); sub.unsubscribe(); pub.unadvertise(); ok(); });
  pub.advertise();
  // ROS drops messages published before the TCPROS link exists: resend until one arrives.
  const iv = setInterval(() => { sent += 1; pub.publish({ data: 'hi' }); }, 50);
}));

await check('call rosapi service', () => step('get_time', (ok, bad) => {
  new Service({ ros, name: '/rosapi/get_time', serviceType: 'rosapi/GetTime' })
    .callService({}, (r) => { assert(r.time.secs > 0, JSON.stringify(r)); ok(); }, bad);
}));

await check('missing service fails (no hang)', () => step('missing', (ok) => {
  new Service({ ros, name: '/rc_missing', serviceType: 'std_srvs/Trigger' })
    .callService({}, () => { throw new Error('unexpected success'); }, (err) => { assert(/does not exist/.test(err), err); ok(); });
}));

await check('client-served service called through ROS', () => step('serve', async (ok, bad) => {
  const served = new Service({ ros, name: '/rc_served', serviceType: 'std_srvs/SetBool' });
  await served.advertise((req, resp) => { resp.success = !req.data; resp.message = 'node'; return true; });
  const caller = new Service({ ros, name: '/rc_served', serviceType: 'std_srvs/SetBool' });
  const tryCall = () => caller.callService({ data: true }, async (r) => {
    assert(r.success === false && r.message === 'node', JSON.stringify(r));
    await served.unadvertise(); ok();
  }, (e) => (/does not exist/.test(e) ? setTimeout(tryCall, 50) : bad(e)));
  tryCall();
}));

await check('params set/get', () => step('param', (ok, bad) => {
  const p = new Param({ ros, name: '/rc_param' });
  p.set({ speed: 0.25, names: ['a'] }, () => p.get((v) => {
    assert(v.speed === 0.25 && v.names[0] === 'a', JSON.stringify(v)); ok();
  }, bad), bad);
}));

await check('message details decode', () => step('details', (ok, bad) => {
  ros.getMessageDetails('geometry_msgs/PoseStamped', (defs) => {
    const decoded = ros.decodeTypeDefs(defs);
    assert('header' in decoded && 'pose' in decoded && 'position' in decoded.pose, JSON.stringify(decoded));
    ok();
  }, bad);
}));

await check('nodes and services lists', () => step('nodes', (ok, bad) => ros.getNodes((nodes) => {
  assert(nodes.includes('/rosapi'), `nodes ${nodes}`);
  ros.getServices((s) => { assert(s.includes('/rosapi/topics'), 'services'); ok(); }, bad);
}, bad)));

clearTimeout(timer);
ros.close();
console.log(failures.length ? `FAILED ${failures.length}` : 'ALL OK');
process.exit(failures.length ? 1 : 0);
