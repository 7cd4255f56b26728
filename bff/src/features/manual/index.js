// Manual motion (feature 4): the robot driver's state, moves, jogging and tool actions. Node: /cell/manual/.
// Every command moves the robot (a tool action moves the gripper), so each needs the control lease; stop never does.
import { defineFeature, featureSchema } from '../../core/features/feature.js';

const MOVES = ['/cell/manual/move_named', '/cell/manual/move_relative', '/cell/manual/move_pose', '/cell/manual/tool'];

/** The motion groups of the manual section, in order. @param {any} section @returns {string[]} */
export function groupNames(section) {
  return (Array.isArray(section?.groups) ? section.groups : [])
    .map((/** @type {{ name?: unknown }} */ g) => g?.name)
    .filter((/** @type {unknown} */ n) => typeof n === 'string' && n !== '');
}

/** Each group's driver state and TCP pose topics: /cell/manual/<group>/state, /cell/manual/<group>/tcp_pose. */
export const stateTopic = (/** @type {string} */ group) => `/cell/manual/${group}/state`;
export const tcpPoseTopic = (/** @type {string} */ group) => `/cell/manual/${group}/tcp_pose`;

export default defineFeature({
  id: 'manual',
  title: 'Manual motion',
  schema: featureSchema('manual'),
  view: (section) => section,
  // Every arm publishes its own joints on /joint_states (the cell file's joint names) and each group its own state.
  // preview_move only computes where a move would go (the 3D view's ghost) and moves nothing: a read, no lease.
  reads: (section) => ({
    subscribe: ['/joint_states', ...groupNames(section).flatMap((g) => [stateTopic(g), tcpPoseTopic(g)])],
    call_service: ['/cell/manual/groups', '/cell/manual/get_pose', '/cell/manual/preview_move'],
  }),
  commands: () => ({ publish: ['/cell/manual/jog'], call_service: MOVES }),
  motion: () => ({ publish: ['/cell/manual/jog'], call_service: MOVES }),
  stop: () => ({ call_service: ['/cell/manual/stop'] }),
  stamped: ['/cell/manual/jog'],
  robotStop: { service: '/cell/manual/stop', type: 'std_srvs/Trigger' },
});
