// The arms of the scene section as the view, the grants and the routes need them: each one's motion group (of
// manual.groups), where its URDF comes from, its joint states topic and its base pose. Plain functions of the cell.
import fs from 'node:fs';
import path from 'node:path';

/** The URL the app fetches an arm's URDF from (mesh filenames rewritten to the mesh route). @param {string} group */
export const urdfUrl = (group) => `/api/scene/arms/${group}/urdf`;

/** The default joint states topic of a group that is not driven through ros_control. */
export const DEFAULT_JOINT_STATES = '/joint_states';

/**
 * Where an arm's URDF comes from: a ROS parameter or a file (as written in the cell file, relative to its
 * directory), and the cell-file field that says so (for messages).
 * @typedef {{kind: 'param', name: string, field: string} | {kind: 'file', file: string, field: string}} UrdfSource
 */

/**
 * @typedef {object} ArmSpec
 * @property {string} group
 * @property {number} groupIndex index in manual.groups (-1: not a group)
 * @property {string[]} joints the group's joints
 * @property {string} joint_states
 * @property {[number, number, number, number]} base x, y, z (m), yaw (deg)
 * @property {string | null} base_frame the TF frame that places the base instead (needs scene.fixed_frame)
 * @property {UrdfSource | null} source null: none given and the group has none (check reports it)
 */

/** @param {any} cell @returns {any[]} */
const groupsOf = (cell) => (Array.isArray(cell?.manual?.groups) ? cell.manual.groups : []);

/**
 * @param {any} arm one entry of scene.arms @param {number} i its index @param {any} cell
 * @returns {ArmSpec}
 */
export function armSpec(arm, i, cell) {
  const groups = groupsOf(cell);
  const groupIndex = groups.findIndex((g) => g?.name === arm.group);
  const g = groupIndex >= 0 ? groups[groupIndex] : null;
  const rc = g?.driver === 'ros_control' ? g.ros_control || {} : null;
  /** @type {UrdfSource | null} */
  let source = null;
  if (arm.robot_description !== undefined) source = { kind: 'param', name: arm.robot_description, field: `scene.arms[${i}].robot_description` };
  else if (arm.urdf !== undefined) source = { kind: 'file', file: arm.urdf, field: `scene.arms[${i}].urdf` };
  else if (rc?.robot_description !== undefined) source = { kind: 'param', name: rc.robot_description, field: `manual.groups[${groupIndex}].ros_control.robot_description` };
  else if (rc?.urdf !== undefined) source = { kind: 'file', file: rc.urdf, field: `manual.groups[${groupIndex}].ros_control.urdf` };
  const base = Array.isArray(arm.base) && arm.base.length === 4 ? arm.base : [0, 0, 0, 0];
  return {
    group: arm.group,
    groupIndex,
    joints: Array.isArray(g?.joints) ? [...g.joints] : [],
    joint_states: arm.joint_states ?? rc?.joint_states ?? DEFAULT_JOINT_STATES,
    base: /** @type {[number, number, number, number]} */ ([...base]),
    base_frame: typeof arm.base_frame === 'string' ? arm.base_frame : null,
    source,
  };
}

/** Every arm of the section, in order. @param {any} section @param {any} cell @returns {ArmSpec[]} */
export const armSpecs = (section, cell) => (Array.isArray(section?.arms) ? section.arms : []).map((a, i) => armSpec(a, i, cell));

/**
 * An arm's URDF file as an absolute path: relative paths are relative to the cell file's directory.
 * @param {string} file @param {string} cellDir
 */
export const urdfPath = (file, cellDir) => path.resolve(cellDir, file);

/** @param {string} p */
function isFile(p) {
  try {
    return fs.statSync(p).isFile();
  } catch {
    return false;
  }
}

/**
 * What the schema cannot say about the section, each problem naming its field. The cell-file loader gives a
 * feature's check no file name, so only absolute `urdf` paths are checked for existence here; the relative ones
 * (relative to the cell file's directory) are checked when the routes are built at start (urdfFileProblems).
 * @param {any} section @param {any} cell
 * @returns {string[]}
 */
export function checkScene(section, cell) {
  const problems = [];
  const groups = groupsOf(cell);
  const known = groups.map((g) => g?.name).filter((n) => typeof n === 'string');
  /** @type {Map<string, number>} */
  const seen = new Map();
  (section?.arms || []).forEach((arm, i) => {
    const where = `scene.arms[${i}]`;
    const g = groups.find((x) => x?.name === arm.group);
    if (!g) {
      problems.push(`${where}.group: "${arm.group}" is not a motion group of manual.groups (${known.length ? `known: ${known.join(', ')}` : 'the cell file has none'})`);
      return;
    }
    if (seen.has(arm.group)) problems.push(`${where}.group: "${arm.group}" is already drawn by scene.arms[${seen.get(arm.group)}] (one entry per group)`);
    else seen.set(arm.group, i);
    if (arm.base_frame !== undefined && section?.fixed_frame === undefined) problems.push(`${where}.base_frame: needs scene.fixed_frame (the frame TF places the base in)`);
    if (arm.base_frame !== undefined && arm.base !== undefined) problems.push(`${where}: give base or base_frame, not both`);
    if (arm.robot_description !== undefined && arm.urdf !== undefined) {
      problems.push(`${where}: give robot_description or urdf, not both`);
      return;
    }
    if (arm.robot_description === undefined && arm.urdf === undefined && g.driver !== 'ros_control') {
      problems.push(`${where}: needs robot_description (a ROS parameter) or urdf (a file): the group "${arm.group}" has driver ${g.driver ?? 'ur_rtde'}, and only a ros_control group names its URDF itself`);
      return;
    }
    if (typeof arm.urdf === 'string' && path.isAbsolute(arm.urdf) && !isFile(arm.urdf)) problems.push(`${where}.urdf: no such file: ${arm.urdf}`);
  });
  return problems;
}

/**
 * The existence of every relative `scene.arms[].urdf` file, checked against the cell file's directory (the routes
 * do it at start: the cell-file loader gives a feature's check no file name). @param {any} section @param {string} cellDir
 * @returns {string[]}
 */
export function urdfFileProblems(section, cellDir) {
  return (section?.arms || []).flatMap((arm, i) => (typeof arm.urdf === 'string' && !path.isAbsolute(arm.urdf) && !isFile(urdfPath(arm.urdf, cellDir))
    ? [`scene.arms[${i}].urdf: no such file: ${arm.urdf} (relative to the cell file's directory ${cellDir})`] : []));
}
