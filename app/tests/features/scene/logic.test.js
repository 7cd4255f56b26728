import { describe, it, expect } from 'vitest';
import URDFLoader from 'urdf-loader';
import {
  sceneSection, pickJoints, parseUrdf, urdfJoints, missingJoints, mimicValues, staleness, staleText, applyMarkers,
  presetPose, formatJoint, routinePath, placeShapes, armBase, frameCap, FRAME_COST_MS,
} from '../../../src/lib/features/scene/logic.js';
import { TfTree, baseToPose, compose, invert, rotate, yawDeg } from '../../../src/lib/features/scene/tf.js';

/** A geometry_msgs/TransformStamped. @param {string} parent @param {string} child @param {number[]} p @param {number[]} [q] */
const tfs = (parent, child, p, q = [0, 0, 0, 1]) => ({
  header: { frame_id: parent }, child_frame_id: child,
  transform: { translation: { x: p[0], y: p[1], z: p[2] }, rotation: { x: q[0], y: q[1], z: q[2], w: q[3] } },
});
const YAW90 = [0, 0, Math.SQRT1_2, Math.SQRT1_2];
/** @param {number[]} a @param {number[]} b */
const near = (a, b) => a.forEach((v, i) => expect(v).toBeCloseTo(b[i], 9));

// A two-joint arm with a two-finger gripper whose right finger mimics the left one (as a gripper URDF does).
const URDF = `<?xml version="1.0"?>
<robot name="t">
  <link name="base"/><link name="l1"><visual><geometry><box size="0.1 0.1 0.3"/></geometry></visual></link>
  <link name="l2"/><link name="fl"/><link name="fr"/><link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/><limit lower="-3.14" upper="3.14" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/></joint>
  <joint name="finger_left" type="prismatic"><parent link="l2"/><child link="fl"/><axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/></joint>
  <joint name="finger_right" type="prismatic"><parent link="l2"/><child link="fr"/><axis xyz="0 -1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/><mimic joint="finger_left" multiplier="1" offset="0"/></joint>
  <joint name="tcp" type="fixed"><parent link="l2"/><child link="tool"/></joint>
</robot>`;

describe('scene logic', () => {
  it('takes the scene section as the server gives it, with defaults for what is missing', () => {
    const s = sceneSection({ arms: [{ group: 'arm', joints: ['j1'], urdf_url: '/api/scene/arms/arm/urdf' }, { group: 'x' }] });
    expect(s).toEqual({
      markers: null, fixed_frame: null, stale_after_s: 1,
      arms: [{ group: 'arm', joints: ['j1'], joint_states: '/joint_states', base: [0, 0, 0, 0], base_frame: null, urdf_url: '/api/scene/arms/arm/urdf' }],
    });
    // a base frame counts only with a fixed frame to place it in
    const tf = sceneSection({ fixed_frame: 'world', arms: [{ group: 'arm', base_frame: 'arm_base', urdf_url: '/u' }] });
    expect([tf.fixed_frame, tf.arms[0].base_frame]).toEqual(['world', 'arm_base']);
    expect(sceneSection({ arms: [{ group: 'arm', base_frame: 'arm_base', urdf_url: '/u' }] }).arms[0].base_frame).toBeNull();
    expect(sceneSection(undefined).arms).toEqual([]);
    expect(sceneSection({ markers: '/sim/parts', stale_after_s: 3, arms: [] }).markers).toBe('/sim/parts');
  });

  it('picks the group\'s joints from a joint state that also carries another arm\'s', () => {
    const msg = { name: ['left_j1', 'right_j1', 'left_j2'], position: [0.1, 0.2, 0.3] };
    expect(pickJoints(msg, ['left_j1', 'left_j2'])).toEqual({ left_j1: 0.1, left_j2: 0.3 });
    expect(pickJoints(msg, ['other'])).toBeNull();
    expect(pickJoints({ name: ['a'], position: [NaN] }, ['a'])).toBeNull();
    expect(pickJoints(null, ['a'])).toBeNull();
  });

  it('reads the URDF\'s movable joints: names, types, limits and mimic joints', () => {
    const joints = urdfJoints(parseUrdf(URDF));
    expect(joints.map((j) => j.name)).toEqual(['j1', 'j2', 'finger_left', 'finger_right']);
    expect(joints[0]).toMatchObject({ type: 'revolute', lower: -3.14, upper: 3.14, mimic: null });
    expect(joints[1]).toMatchObject({ type: 'continuous', lower: null, upper: null });
    expect(joints[3].mimic).toEqual({ joint: 'finger_left', multiplier: 1, offset: 0 });
    expect(mimicValues(joints, { finger_left: 0.02 })).toEqual({ finger_right: 0.02 });
    // The cell file names joints the URDF does not move (a mimic joint is not one the driver sends).
    expect(missingJoints(joints, ['j1', 'j2', 'j3', 'finger_right'])).toEqual(['j3', 'finger_right']);
  });

  it('says what is wrong with a URDF that does not parse or is no robot', () => {
    expect(() => parseUrdf('<robot><link></robot>')).toThrow(/not valid XML/);
    expect(() => parseUrdf('<sdf/>')).toThrow(/<sdf>, not <robot>/);
  });

  it('builds the scene from the URDF (urdf-loader): joints move their links, a mimic finger follows its leader', () => {
    const robot = new URDFLoader().parse(URDF);
    expect(Object.keys(robot.joints).sort()).toEqual(['finger_left', 'finger_right', 'j1', 'j2', 'tcp']);
    robot.joints.j1.setJointValue(0.5);
    expect(robot.joints.j1.angle).toBeCloseTo(0.5, 9);
    expect(robot.joints.j1.quaternion.z).toBeCloseTo(Math.sin(0.25), 9); // the joint turns its child link
    robot.joints.finger_left.setJointValue(0.03);
    expect(robot.joints.finger_right.angle).toBeCloseTo(0.03, 9);
    // A limit stops the drawn value unless the view turns limits off (it draws what the arm reports).
    robot.joints.j1.setJointValue(4);
    expect(robot.joints.j1.angle).toBeCloseTo(3.14, 9);
    robot.joints.j1.ignoreLimits = true;
    robot.joints.j1.setJointValue(4);
    expect(robot.joints.j1.angle).toBeCloseTo(4, 9);
  });

  it('marks joint states older than the cell\'s limit stale, and none yet too', () => {
    expect(staleness(null, 1000, 1)).toEqual({ stale: true, ageS: null });
    expect(staleness(1000, 1800, 1)).toEqual({ stale: false, ageS: 0.8 });
    expect(staleness(1000, 3500, 1)).toEqual({ stale: true, ageS: 2.5 });
    expect(staleText(2.5)).toBe('Stale: joint states 2.5 s old');
    expect(staleText(null)).toBe('No joint states yet');
  });

  it('applies markers by ns/id: add, modify, delete, delete all; other types counted, not drawn', () => {
    const shapes = new Map();
    const cube = (/** @type {number} */ id, /** @type {number} */ x) => ({ ns: 'parts', id, type: 1, action: 0, pose: { position: { x, y: 0, z: 0.025 }, orientation: { x: 0, y: 0, z: 0, w: 1 } }, scale: { x: 0.05, y: 0.05, z: 0.05 }, color: { r: 1, g: 0, b: 0, a: 1 } });
    expect(applyMarkers(shapes, { markers: [cube(0, 0.1), cube(1, 0.2), { ns: 'x', id: 0, type: 9, action: 0 }] })).toEqual({ skipped: 1 });
    expect([...shapes.keys()]).toEqual(['parts/0', 'parts/1']);
    expect(shapes.get('parts/0')).toEqual({ key: 'parts/0', shape: 'cube', frame: '', position: [0.1, 0, 0.025], quaternion: [0, 0, 0, 1], scale: [0.05, 0.05, 0.05], color: [1, 0, 0, 1] });
    applyMarkers(shapes, { markers: [cube(0, 0.3), { ns: 'parts', id: 1, action: 2 }] });
    expect(shapes.get('parts/0')?.position[0]).toBe(0.3);
    expect(shapes.has('parts/1')).toBe(false);
    applyMarkers(shapes, { markers: [{ ...cube(5, 0), ns: 'stations', type: 3, pose: { position: {}, orientation: { x: 0, y: 0, z: 0, w: 0 } } }] });
    expect(shapes.get('stations/5')?.quaternion).toEqual([0, 0, 0, 1]);
    applyMarkers(shapes, { markers: [{ ns: 'parts', action: 3 }] });
    expect([...shapes.keys()]).toEqual(['stations/5']);
    applyMarkers(shapes, { markers: [{ action: 3 }] });
    expect(shapes.size).toBe(0);
  });

  it('TF: chains of frames composed, looked up from any frame to any other of the same tree', () => {
    const tree = new TfTree();
    // world -> left_base (0.5 m along x, turned 90 degrees) -> tool (0.1 m along its x); world -> camera
    expect(tree.apply({ transforms: [tfs('world', 'left_base', [0.5, 0, 0], YAW90), tfs('/left_base', 'tool', [0.1, 0, 0]), tfs('world', 'camera', [0, 0, 2])] })).toBe(3);
    const tool = tree.lookup('world', 'tool');
    near(tool?.p ?? [], [0.5, 0.1, 0]); // the base's x is the world's y
    near(tool?.q ?? [], YAW90);
    // from a sibling branch: the tool seen from the camera
    near(tree.lookup('camera', 'tool')?.p ?? [], [0.5, 0.1, -2]);
    near(tree.lookup('tool', 'world')?.p ?? [], invert(tool ?? { p: [], q: [] }).p);
    expect(tree.lookup('world', 'world')).toEqual({ p: [0, 0, 0], q: [0, 0, 0, 1] });
    expect(tree.lookup('world', 'nowhere')).toBeNull();
    tree.apply({ transforms: [tfs('map', 'odom', [1, 0, 0])] });
    expect(tree.lookup('world', 'odom')).toBeNull(); // another tree: not linked
    // the same transform again changes nothing; a newer one moves the frame
    expect(tree.apply({ transforms: [tfs('world', 'camera', [0, 0, 2])] })).toBe(0);
    expect(tree.apply({ transforms: [tfs('world', 'camera', [0, 0, 3])] })).toBe(1);
    near(tree.lookup('camera', 'tool')?.p ?? [], [0.5, 0.1, -3]);
  });

  it('TF: what is not a transform, or would close a loop, is skipped; quaternions are normalised', () => {
    const tree = new TfTree();
    expect(tree.apply({ transforms: [tfs('a', 'b', [1, 0, 0]), tfs('b', 'a', [1, 0, 0]), tfs('b', 'b', [0, 0, 0]),
      tfs('a', 'c', [NaN, 0, 0]), tfs('a', 'd', [0, 0, 0], [0, 0, 0, 0]), tfs('', 'e', [0, 0, 0]), null] })).toBe(1);
    expect(tree.apply(undefined)).toBe(0);
    expect([...tree.frames.keys()]).toEqual(['b']);
    tree.apply({ transforms: [tfs('a', 'f', [0, 0, 0], [0, 0, 2, 2])] });
    near(tree.lookup('a', 'f')?.q ?? [], YAW90);
  });

  it('pose helpers: a base [x, y, z, yaw deg] as a pose, compose and invert undo each other', () => {
    near(baseToPose([-0.48, 0, 0, 180]).q, [0, 0, 1, 0]);
    expect(yawDeg(baseToPose([0, 0, 0, -135]).q)).toBeCloseTo(-135, 9);
    expect(yawDeg(compose({ p: [0, 0, 0], q: YAW90 }, { p: [0, 0, 0], q: [Math.SQRT1_2, 0, 0, Math.SQRT1_2] }).q)).toBeCloseTo(90, 9); // a roll keeps the heading
    near(rotate(baseToPose([0, 0, 0, 90]).q, [1, 0, 0]), [0, 1, 0]);
    const a = { p: [0.3, -0.2, 0.1], q: YAW90 };
    const id = compose(a, invert(a));
    near(id.p, [0, 0, 0]);
    near(id.q, [0, 0, 0, 1]);
  });

  it('with a fixed frame, markers in other frames are drawn where TF puts them; unknown frames left out and counted', () => {
    const tree = new TfTree();
    tree.apply({ transforms: [tfs('world', 'table', [1, 2, 0.7], YAW90)] });
    const shape = (/** @type {string} */ frame, /** @type {string} */ key) => ({ key, shape: /** @type {const} */ ('cube'), frame, position: [0.1, 0, 0], quaternion: [0, 0, 0, 1], scale: [1, 1, 1], color: [1, 1, 1, 1] });
    const list = [shape('world', 'a'), shape('', 'b'), shape('table', 'c'), shape('camera', 'd'), shape('camera', 'e')];
    const placed = placeShapes(list, 'world', tree);
    expect(placed.shapes.map((s) => s.key)).toEqual(['a', 'b', 'c']);
    near(placed.shapes[2].position, [1, 2.1, 0.7]);
    near(placed.shapes[2].quaternion, YAW90);
    expect(placed.unplaced).toEqual({ camera: 2 });
    // no fixed frame: no TF, drawn as given
    expect(placeShapes(list, null, tree)).toEqual({ shapes: list, unplaced: {} });
  });

  it('an arm\'s base: from TF when it names a base frame (none until TF has it), else the cell file\'s', () => {
    const tree = new TfTree();
    const arm = { group: 'left', joints: [], joint_states: '/joint_states', base: [0, 0, 0, 0], base_frame: 'left_base_link', urdf_url: '/u' };
    expect(armBase(arm, 'world', tree)).toBeNull();
    tree.apply({ transforms: [tfs('world', 'left_base_link', [-0.48, 0, 0], [0, 0, 1, 0])] });
    near(armBase(arm, 'world', tree)?.p ?? [], [-0.48, 0, 0]);
    near(armBase({ ...arm, base_frame: null, base: [0.48, 0, 0, 90] }, 'world', tree)?.q ?? [], YAW90);
  });

  it('camera presets look at the centre from the front, the side and the top, far enough to see it all', () => {
    const front = presetPose('front', [0, 0, 0.5], 1, 45, 1);
    expect(front.target).toEqual([0, 0, 0.5]);
    expect(front.position[0]).toBeLessThan(-1);
    expect(front.position[0]).toBeLessThan(front.position[1]); // mostly from the front
    const top = presetPose('top', [0, 0, 0.5], 1, 45, 1);
    expect(top.position[2]).toBeGreaterThan(2.5);
    expect(Math.hypot(top.position[0], top.position[1])).toBeLessThan(0.01);
    const side = presetPose('side', [0, 0, 0.5], 1, 45, 1);
    expect(side.position[1]).toBeGreaterThan(1);
    // A narrow (portrait) view backs off further so the width fits too.
    const d = (/** @type {{ position: number[] }} */ p) => Math.hypot(p.position[0], p.position[1], p.position[2] - 0.5);
    expect(d(presetPose('front', [0, 0, 0.5], 1, 45, 0.5))).toBeGreaterThan(d(front));
  });

  it('formats a joint value in rad and degrees', () => {
    expect(formatJoint(Math.PI / 2)).toBe('1.571 rad (90.0°)');
  });

  it('a routine\'s path: the positions of its pose steps, in order (tool actions have none)', () => {
    const steps = [
      { kind: 'pose', pose: [0.1, 0.2, 0.3, 0, 3.14, 0] },
      { kind: 'action', pose: [] },
      { kind: 'pose', pose: [0.1, 0.2, 0.5, 0, 3.14, 0] },
      { kind: 'pose', pose: [NaN, 0, 0, 0, 0, 0] },
    ];
    expect(routinePath({ name: 'r', group: 'arm', steps })).toEqual({ name: 'r', group: 'arm', points: [[0.1, 0.2, 0.3], [0.1, 0.2, 0.5]] });
  });
});

describe('frameCap', () => {
  it('a desktop draws up to 60 frames a second while its frames are cheap, 30 once they cost more', () => {
    expect(frameCap({ coarse: false, frameMs: 0 })).toBe(60);
    expect(frameCap({ coarse: false, frameMs: FRAME_COST_MS })).toBe(60);
    expect(frameCap({ coarse: false, frameMs: FRAME_COST_MS + 0.1 })).toBe(30);
  });
  it('a touch device keeps to 30 however cheap its frames', () => {
    expect(frameCap({ coarse: true, frameMs: 0 })).toBe(30);
  });
});
