// Manual motion (feature 4): the robot driver's state, moves, jogging and tool actions. Node: /cell/manual/.
// Every command moves the robot (a tool action moves the gripper), so each needs the control lease; stop never does.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

const MOVES = ['/cell/manual/move_named', '/cell/manual/move_relative', '/cell/manual/move_pose', '/cell/manual/tool'];

export default defineFeature({
  id: 'manual',
  title: 'Manual motion',
  schema: featureSchema('manual'),
  view: (section) => section,
  reads: () => ({
    subscribe: ['/joint_states', '/cell/manual/state', '/cell/manual/tcp_pose'],
    call_service: ['/cell/manual/groups', '/cell/manual/get_pose'],
  }),
  commands: () => ({ publish: ['/cell/manual/jog'], call_service: MOVES }),
  motion: () => ({ publish: ['/cell/manual/jog'], call_service: MOVES }),
  stop: () => ({ call_service: ['/cell/manual/stop'] }),
  robotStop: { service: '/cell/manual/stop', type: 'std_srvs/Trigger' },
});
