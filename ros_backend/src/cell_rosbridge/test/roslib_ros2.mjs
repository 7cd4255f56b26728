// roslib 2.x (the app's client library) against our rosbridge server on ROS 2, run under Node by
// test_actions_ros2.py. Usage: node roslib_ros2.mjs <port> <node name of the server>. Prints "ok <check>" per
// check; exit 0 only if all pass. Expects the FollowJointTrajectory test server on /test_arm/follow_joint_trajectory.
import { Action, Ros, Service, Topic } from 'roslib';

const [port, server] = process.argv.slice(2);
const failures = [];
const timer = setTimeout(() => { console.log('FAIL global timeout'); process.exit(2); }, 40000);

function step(name, fn, ms = 10000) {
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
const action = new Action({ ros, name: '/test_arm/follow_joint_trajectory',
  actionType: 'control_msgs/action/FollowJointTrajectory' });
const goal = (joints, n) => ({ trajectory: { joint_names: joints, points: Array.from({ length: n }, (_, i) => ({
  positions: joints.map(() => 0.1 * (i + 1)), time_from_start: { sec: i + 1, nanosec: 0 } })) } });

await check('topic echo with ROS 2 type names', () => step('echo', (ok) => {
  const sub = new Topic({ ros, name: '/rl2_echo', messageType: 'std_msgs/msg/String' });
  const pub = new Topic({ ros, name: '/rl2_echo', messageType: 'std_msgs/msg/String' });
  sub.subscribe((m) => { assert(m.data === 'hi', JSON.stringify(m)); sub.unsubscribe(); clearInterval(again); ok(); });
  const again = setInterval(() => pub.publish({ data: 'hi' }), 100);
}));

await check('an action goal: feedback, then its result', () => step('goal', (ok, bad) => {
  const feedback = [];
  // The first goal to an action makes the server's action client (its feedback reader matches meanwhile: see
  // test_actions_ros2.py); the goal under test follows its result.
  action.sendGoal(goal(['j1'], 1), () => action.sendGoal(goal(['j1', 'j2'], 3), (result) => {
    assert(result.error_string === '3 points' && result.error_code === 0, JSON.stringify(result));
    assert(feedback.length >= 1 && feedback[0].joint_names.length === 2, JSON.stringify(feedback));
    ok();
  }, (fb) => feedback.push(fb), bad), () => {}, bad);
}));

await check('a canceled goal fails with its status', () => step('cancel', (ok) => {
  let id = null;
  id = action.sendGoal(goal(['hold'], 1), () => { throw new Error('a held goal succeeded'); },
    () => { if (id) { action.cancelGoal(id); id = null; } },
    (err) => { assert(/5|cancel/i.test(String(err)), String(err)); ok(); });
}));

await check('a ROS 2 node parameter service', () => step('params', (ok, bad) => {
  new Service({ ros, name: `/${server}/get_parameters`, serviceType: 'rcl_interfaces/srv/GetParameters' })
    .callService({ names: ['port'] }, (r) => { assert(r.values[0].integer_value === Number(port), JSON.stringify(r)); ok(); }, bad);
}));

clearTimeout(timer);
ros.close();
console.log(failures.length ? `FAILED: ${failures.join(', ')}` : 'ALL OK');
process.exit(failures.length ? 1 : 0);
