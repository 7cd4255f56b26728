"""The ros_control backend's kinematics (KDL from a URDF) and trajectory building, in plain Python (no ROS).

The arm is the KUKA LBR iiwa of pybullet_data, renamed to iiwa_* and given a fixed tool link 0.06 m along the
flange z axis, as the simulated cell publishes it; pybullet's own forward kinematics is the reference. The UR5
URDF of the UR sim, checked against the sim's DH kinematics, shows nothing here is iiwa-specific.
"""
from __future__ import annotations

import math
import os
import re
import xml.etree.ElementTree as ET

import numpy as np
import pybullet as p
import pybullet_data
import pytest

from cell_nodes.manual import frames
from cell_nodes.manual.limits import TCP_SPEED_CAP
from cell_nodes.manual.ros_control.kinematics import Kinematics, KinematicsError
from cell_nodes.manual.ros_control.trajectory import (MAX_STEP, MAX_STEP_ANGLE, TrajectoryError, TrajectoryPoint,
                                                      jog_joint_velocities, jog_point, joint_move, linear_move,
                                                      linear_path)
from sim import kinematics as ur_kin
from sim import urdf as ur_urdf

TOOL_LENGTH = 0.06
HOME = [0.0, 0.5, 0.0, -1.4, 0.0, 1.2, 0.0]
IIWA_JOINTS = [f"iiwa_joint_{i}" for i in range(1, 8)]


def iiwa_urdf() -> str:
    with open(os.path.join(pybullet_data.getDataPath(), "kuka_iiwa/model.urdf")) as fh:
        text = fh.read().replace("lbr_iiwa_", "iiwa_")
    tool = (f'<link name="iiwa_link_ee"/><joint name="iiwa_joint_ee" type="fixed"><parent link="iiwa_link_7"/>'
            f'<child link="iiwa_link_ee"/><origin xyz="0 0 {TOOL_LENGTH}" rpy="0 0 0"/></joint>')
    return text.replace("</robot>", tool + "</robot>")


@pytest.fixture(scope="module")
def kin() -> Kinematics:
    return Kinematics.from_urdf(iiwa_urdf(), "iiwa_link_0", "iiwa_link_ee")


@pytest.fixture(scope="module")
def ur5() -> Kinematics:
    return Kinematics.from_urdf(ur_urdf.urdf_text("vacuum"), "base_link", ur_urdf.CUP_LINK)


def random_q(k: Kinematics, rng: np.random.Generator, frac: float = 0.9) -> list[float]:
    return [float(rng.uniform(lo * frac, hi * frac)) for lo, hi in zip(k.lower, k.upper)]


def hermite(a: TrajectoryPoint, b: TrajectoryPoint, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """What a joint_trajectory_controller does between two points given position and velocity."""
    dt = b.time_from_start - a.time_from_start
    p0, p1 = np.array(a.positions), np.array(b.positions)
    v0, v1 = np.array(a.velocities) * dt, np.array(b.velocities) * dt
    t2, t3 = tau * tau, tau * tau * tau
    pos = (2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + tau) * v0 + (-2 * t3 + 3 * t2) * p1 + (t3 - t2) * v1
    vel = ((6 * t2 - 6 * tau) * p0 + (3 * t2 - 4 * tau + 1) * v0 + (-6 * t2 + 6 * tau) * p1 + (3 * t2 - 2 * tau) * v1) / dt
    return pos, vel


def with_start(q0, points):
    return [TrajectoryPoint(list(q0), [0.0] * len(q0), 0.0)] + list(points)


# ---- the URDF and the chain -------------------------------------------------------------------------------
def test_chain_from_the_iiwa_urdf(kin):
    assert kin.joint_names == IIWA_JOINTS
    assert kin.n == 7
    assert kin.lower[0] == pytest.approx(-2.96705972839) and kin.upper[0] == pytest.approx(2.96705972839)
    assert kin.lower[3] == pytest.approx(-2.09439510239) and kin.upper[6] == pytest.approx(3.05432619099)
    assert kin.velocity_limits == [10.0] * 7


def test_fk_matches_pybullet(kin, tmp_path):
    # pybullet cannot find the meshes from a copied file: drop visuals and collisions (frames do not use them).
    root = ET.fromstring(iiwa_urdf())
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                link.remove(el)
    path = tmp_path / "iiwa.urdf"
    path.write_text(ET.tostring(root, encoding="unicode"))
    client = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(path), useFixedBase=True, physicsClientId=client)
        names = [p.getJointInfo(body, i, physicsClientId=client)[1].decode()
                 for i in range(p.getNumJoints(body, physicsClientId=client))]
        ee = names.index("iiwa_joint_ee")   # pybullet's link index = its parent joint's index
        rng = np.random.default_rng(3)
        configs = [[0.0] * 7, HOME] + [random_q(kin, rng, 1.0) for _ in range(8)]
        for q in configs:
            for i, name in enumerate(IIWA_JOINTS):
                p.resetJointState(body, names.index(name), q[i], physicsClientId=client)
            state = p.getLinkState(body, ee, computeForwardKinematics=True, physicsClientId=client)
            pose = kin.fk(q)
            assert np.linalg.norm(np.array(state[4]) - pose[:3]) < 1e-6, q
            r_bullet = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
            assert np.abs(r_bullet - frames.rotvec_to_matrix(pose[3:])).max() < 1e-6, q
    finally:
        p.disconnect(client)


def test_fk_of_the_tool_link(kin):
    # straight up, every joint 0: the TCP on the base z axis, 1.26 m + the tool high, tool z pointing up
    pose = kin.fk([0.0] * 7)
    assert pose[:3] == pytest.approx([0.0, 0.0, 0.1575 + 0.2025 + 0.2045 + 0.2155 + 0.1845 + 0.2155 + 0.081 + TOOL_LENGTH],
                                     abs=1e-9)


def test_joint_kinds_limits_and_soft_limits():
    xml = """<robot name="toy">
      <link name="base"/><link name="slider"/><link name="rotor"/><link name="tip"/><link name="elsewhere"/>
      <joint name="lift" type="prismatic"><parent link="base"/><child link="slider"/><axis xyz="0 0 1"/>
        <limit lower="0" upper="0.5" velocity="0.2" effort="10"/>
        <safety_controller soft_lower_limit="0.01" soft_upper_limit="0.45" k_position="10" k_velocity="1"/></joint>
      <joint name="spin" type="continuous"><parent link="slider"/><child link="rotor"/>
        <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/></joint>
      <joint name="flange" type="fixed"><parent link="rotor"/><child link="tip"/><origin xyz="0.1 0 0"/></joint>
      <joint name="side" type="fixed"><parent link="base"/><child link="elsewhere"/></joint>
    </robot>"""
    k = Kinematics.from_urdf(xml, "base", "tip")
    assert k.joint_names == ["lift", "spin"]
    assert k.lower == [0.01, -math.inf] and k.upper == [0.45, math.inf]
    assert k.velocity_limits == [0.2, math.inf]
    pose = k.fk([0.2, math.pi / 2])
    assert pose == pytest.approx([0.3, 0.1, 0.2, 0.0, 0.0, math.pi / 2], abs=1e-12)
    # a continuous joint comes back the whole turns nearest the seed
    q = k.ik(pose, [0.25, 2 * math.pi + 1.4])
    assert q is not None and q == pytest.approx([0.2, 2 * math.pi + math.pi / 2], abs=1e-6)
    # out of the (soft) limits of the prismatic joint: refused
    assert k.ik(k.fk([0.48, 0.0]), [0.3, 0.0]) is None


# ---- error messages -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("xml, base, tip, message", [
    ("<robot name='x'><link name='a'>", "a", "b", "not valid XML"),
    ("", "a", "b", "not valid XML"),
    ("<sdf/>", "a", "b", "not a URDF"),
    (None, "iiwa_link_0", "iiwa_link_tool", "tip link 'iiwa_link_tool' is not in the robot description"),
    (None, "world", "iiwa_link_ee", "base link 'world' is not in the robot description"),
    (None, "iiwa_link_ee", "iiwa_link_0", "no kinematic chain from 'iiwa_link_ee' to 'iiwa_link_0'"),
    (None, "iiwa_link_7", "iiwa_link_ee", "has no movable joint"),
])
def test_bad_descriptions_are_refused_with_a_clear_message(xml, base, tip, message):
    with pytest.raises(KinematicsError, match=re.escape(message)) as err:
        Kinematics.from_urdf(iiwa_urdf() if xml is None else xml, base, tip)
    assert isinstance(err.value, ValueError)


def test_missing_link_message_lists_the_links():
    with pytest.raises(KinematicsError) as err:
        Kinematics.from_urdf(iiwa_urdf(), "iiwa_link_0", "tool0")
    assert "iiwa_link_ee" in str(err.value) and "iiwa_link_3" in str(err.value)


def test_unsupported_joint_and_bad_numbers():
    floating = "<robot name='f'><link name='a'/><link name='b'/><joint name='j' type='floating'>" \
               "<parent link='a'/><child link='b'/></joint></robot>"
    with pytest.raises(KinematicsError, match="'floating' is not supported"):
        Kinematics.from_urdf(floating, "a", "b")
    bad = "<robot name='f'><link name='a'/><link name='b'/><joint name='j' type='revolute'>" \
          "<parent link='a'/><child link='b'/><origin xyz='0 zero 0'/></joint></robot>"
    with pytest.raises(KinematicsError, match="joint 'j' origin xyz"):
        Kinematics.from_urdf(bad, "a", "b")


# ---- IK -----------------------------------------------------------------------------------------------------
def test_ik_round_trips(kin):
    rng = np.random.default_rng(7)
    for _ in range(40):
        q = random_q(kin, rng)
        pose = kin.fk(q)
        seed = [v + float(rng.uniform(-0.3, 0.3)) for v in q]
        sol = kin.ik(pose, seed)
        assert sol is not None, q
        assert kin.within_limits(sol)
        dpos, dang = kin.pose_error(sol, pose)
        assert dpos < 1e-5 and dang < 1e-4
    # far seeds: the restarts find a solution too
    for _ in range(10):
        pose = kin.fk(random_q(kin, rng))
        sol = kin.ik(pose, HOME)
        assert sol is not None and kin.within_limits(sol)
        assert frames.pose_distance(kin.fk(sol), pose)[0] < 1e-5


def test_ik_stays_near_the_seed(kin):
    q = HOME
    pose = kin.fk(q)
    pose[2] -= 0.002
    sol = kin.ik(pose, q)
    assert sol is not None and max(abs(a - b) for a, b in zip(sol, q)) < 0.02


def test_unreachable_pose_has_no_ik(kin):
    assert kin.ik([2.0, 0.0, 0.5, 0.0, math.pi, 0.0], HOME) is None          # 2 m away: the arm reaches ~1.3
    assert kin.ik([0.0, 0.0, 1.4, 0.0, 0.0, 0.0], HOME) is None              # above the stretched arm


def test_ik_respects_joint_limits(ur5):
    # UR5 with the shoulder pan limited to +-0.3 rad: a pose that needs pan 1.0 (or its shoulder flip) is refused
    xml = ur_urdf.urdf_text("vacuum")
    xml = xml.replace('<joint name="shoulder_pan_joint" type="revolute"><parent link="base_link"/><child link="link_1"/>'
                      '<origin xyz="0.000000 0 0.000000" rpy="0.000000000 0 0"/><axis xyz="0 0 1"/>'
                      '<limit lower="-6.283185" upper="6.283185"',
                      '<joint name="shoulder_pan_joint" type="revolute"><parent link="base_link"/><child link="link_1"/>'
                      '<origin xyz="0.000000 0 0.000000" rpy="0.000000000 0 0"/><axis xyz="0 0 1"/>'
                      '<limit lower="-0.3" upper="0.3"')
    narrow = Kinematics.from_urdf(xml, "base_link", ur_urdf.CUP_LINK)
    assert narrow.lower[0] == -0.3
    q = [1.0, -1.2, 1.4, -1.7, -1.5, 0.4]
    pose = narrow.fk(q)
    assert narrow.ik(pose, [0.0, -1.2, 1.4, -1.7, -1.5, 0.4]) is None
    free = narrow.ik(pose, q, within_limits=False, restarts=False)
    assert free is not None and free[0] == pytest.approx(1.0, abs=1e-6)
    # a linear move there: the target has no solution within the limits
    with pytest.raises(TrajectoryError, match=r"^pose unreachable: no joint solution within the joint limits"):
        linear_move(narrow, [0.0, -1.2, 1.4, -1.7, -1.5, 0.4], pose, 0.2, 1.0, 1.0)


# ---- Jacobian and velocities --------------------------------------------------------------------------------
def test_jacobian_matches_finite_differences(kin):
    q = HOME
    j = kin.jacobian(q)
    assert j.shape == (6, 7)
    h = 1e-6
    base = frames.pose_to_matrix(kin.fk(q))
    for i in range(7):
        q2 = list(q)
        q2[i] += h
        moved = frames.pose_to_matrix(kin.fk(q2))
        lin = (moved[:3, 3] - base[:3, 3]) / h
        ang = frames.matrix_to_rotvec(moved[:3, :3] @ base[:3, :3].T) / h
        assert np.allclose(j[:3, i], lin, atol=1e-5) and np.allclose(j[3:, i], ang, atol=1e-5)


def test_twist_to_joint_velocities_and_tcp_speed(kin):
    twist = [0.05, -0.1, 0.02, 0.1, 0.0, -0.2]
    qd = kin.twist_to_joint_velocities(HOME, twist)
    assert kin.tcp_velocity(HOME, qd) == pytest.approx(twist, abs=1e-9)
    assert kin.tcp_speed(HOME, qd) == pytest.approx(math.sqrt(0.05 ** 2 + 0.1 ** 2 + 0.02 ** 2), abs=1e-9)
    # tcp_speed is the speed of the TCP point: one joint turning, speed = rate x distance from its axis
    q = [0.0] * 7
    assert kin.tcp_speed(q, [0.0, 1.0, 0, 0, 0, 0, 0]) == pytest.approx(kin.fk(q)[2] - 0.36, abs=1e-9)


def test_velocity_ik_stays_bounded_at_a_singularity(kin):
    # stretched straight up the TCP cannot move along z: damped least squares answers with bounded joint speeds
    # (and never a faster twist than asked) instead of the pseudo-inverse's racing joints
    for q in ([0.0] * 7, [0.0, 0.01, 0.0, 0.01, 0.0, 0.01, 0.0], [0.0, 0.003, 0.0, -0.003, 0.0, 0.0, 0.0]):
        for twist in ([0.0, 0.0, 0.2, 0.0, 0.0, 0.0], [0.1, 0.0, 0.2, 0.0, 0.0, 0.0], [0.0, 0.1, -0.2, 0.0, 0.3, 0.0]):
            qd = kin.twist_to_joint_velocities(q, twist)
            assert max(abs(v) for v in qd) < 2.0          # the plain pseudo-inverse: ~100-300 rad/s near q
            assert np.linalg.norm(kin.tcp_velocity(q, qd)) <= np.linalg.norm(twist) + 1e-9
    # away from singularities it is exact
    assert kin.tcp_velocity(HOME, kin.twist_to_joint_velocities(HOME, [0, 0, 0.2, 0, 0, 0])) == \
        pytest.approx([0, 0, 0.2, 0, 0, 0], abs=1e-9)


# ---- joint moves --------------------------------------------------------------------------------------------
def test_joint_move_synchronized_trapezoid():
    start = [0.0, 0.5, 0.0, -1.4, 0.0, 1.2, 0.0]
    target = [1.0, 0.2, -0.3, -1.0, 0.5, 0.5, 0.25]
    speed, acc = 0.5, 1.0
    pts = joint_move(start, target, speed, acc, [10.0] * 7, sample_time=0.02)
    d = np.array(target) - np.array(start)
    # joint 1 has the longest way (1 rad): 1/0.5 + 0.5/1 = 2.5 s, the others are stretched to the same time
    assert pts[-1].time_from_start == pytest.approx(2.5)
    assert pts[-1].positions == target and pts[-1].velocities == [0.0] * 7
    prev = TrajectoryPoint(start, [0.0] * 7, 0.0)
    for pt in pts:
        dt = pt.time_from_start - prev.time_from_start
        assert 0 < dt <= 0.02 + 1e-12
        v, v0 = np.array(pt.velocities), np.array(prev.velocities)
        assert np.all(np.abs(v) <= speed + 1e-12)
        assert np.all(np.abs(v - v0) / dt <= acc + 1e-9)
        # the positions are the integral of the (piecewise linear) velocities: cubic interpolation is exact
        assert np.allclose(np.array(pt.positions) - prev.positions, (v + v0) / 2 * dt, atol=1e-9)
        # every joint at the same fraction of its way: they arrive together, on a straight line in joint space
        frac = (np.array(pt.positions) - start) / d
        assert np.allclose(frac, frac[0], atol=1e-12)
        prev = pt
    assert max(abs(v) for pt in pts for v in pt.velocities) == pytest.approx(speed)


def test_joint_move_short_move_and_velocity_limits():
    start = [0.0] * 3
    pts = joint_move(start, [0.01, 0.0, -0.005], 1.0, 2.0, None)
    assert pts[-1].time_from_start == pytest.approx(2 * math.sqrt(0.01 / 2.0))   # a triangle: never at speed
    # a joint whose URDF limit is below the requested speed sets the pace
    pts = joint_move(start, [1.0, 1.0, 0.0], 1.0, 5.0, [0.25, 10.0, 10.0])
    assert max(abs(pt.velocities[0]) for pt in pts) <= 0.25 + 1e-12
    assert pts[-1].time_from_start == pytest.approx(1.0 / 0.25 + 0.25 / 5.0)
    # already there: one point holding the target
    pts = joint_move([0.1, 0.2], [0.1, 0.2], 1.0, 1.0)
    assert len(pts) == 1 and pts[0].positions == [0.1, 0.2] and pts[0].velocities == [0.0, 0.0]
    assert pts[0].time_from_start > 0
    with pytest.raises(TrajectoryError, match="speed"):
        joint_move(start, [1.0, 0, 0], 0.0, 1.0)
    with pytest.raises(TrajectoryError, match="target joints"):
        joint_move(start, [1.0, 0], 1.0, 1.0)


# ---- linear moves -------------------------------------------------------------------------------------------
def _distance_to_segment(x, a, b) -> tuple[float, float]:
    ab = b - a
    s = float(np.clip(np.dot(x - a, ab) / np.dot(ab, ab), 0.0, 1.0))
    return float(np.linalg.norm(x - (a + s * ab))), s


def test_linear_move_is_straight_and_under_the_tcp_cap(kin):
    cap = TCP_SPEED_CAP
    start_pose = kin.fk(HOME)
    target = list(start_pose)
    target[1] += 0.3
    target[2] -= 0.2
    pts = linear_move(kin, HOME, target, cap, 1.0, 2.0)
    a, b = np.array(start_pose[:3]), np.array(target[:3])
    assert kin.pose_error(pts[-1].positions, target)[0] < 1e-5
    assert pts[-1].velocities == [0.0] * 7
    full = with_start(HOME, pts)
    top = 0.0
    prev_xyz = a
    for pt0, pt1 in zip(full, full[1:]):
        assert pt1.time_from_start > pt0.time_from_start
        pose = kin.fk(pt1.positions)
        dist, _ = _distance_to_segment(np.array(pose[:3]), a, b)
        assert dist < 0.0005
        assert frames.pose_distance(pose, start_pose)[1] < 1e-4          # orientation kept
        assert np.linalg.norm(np.array(pose[:3]) - prev_xyz) <= MAX_STEP + 1e-9
        prev_xyz = np.array(pose[:3])
        for tau in (0.0, 0.25, 0.5, 0.75, 1.0):                          # between points too, as interpolated
            q, qd = hermite(pt0, pt1, tau)
            speed = kin.tcp_speed(q, qd)
            top = max(top, speed)
            assert speed <= cap + 1e-9
            assert _distance_to_segment(np.array(kin.fk(q)[:3]), a, b)[0] < 0.0005
    assert top > 0.9 * cap          # it does go (nearly) as fast as allowed


def test_linear_path_is_the_waypoints_linear_move_times(kin):
    """linear_path is what a linear move's target joints come from (the move preview): its last row is exactly where
    linear_move's trajectory ends, whatever the speeds; no motion is the start alone; it refuses as linear_move."""
    target = list(kin.fk(HOME))
    target[1] += 0.1
    target[2] -= 0.05
    target[5] += 0.3
    path = linear_path(kin, HOME, target)
    assert path.qs[0] == pytest.approx(HOME) and path.length == pytest.approx(math.hypot(0.1, 0.05))
    for speed, joint_speed in ((0.25, 2.0), (0.05, 0.2)):
        assert linear_move(kin, HOME, target, speed, 1.0, joint_speed)[-1].positions == pytest.approx(path.qs[-1],
                                                                                                    abs=0)
    assert kin.pose_error(path.qs[-1], target)[0] < 1e-5
    assert len(linear_path(kin, HOME, kin.fk(HOME)).qs) == 1
    upright = kin.fk(HOME)[:3] + [0.0, 0.0, 0.0]
    with pytest.raises(TrajectoryError, match=r"^joint limit: iiwa_joint_6 would pass its limit"):
        linear_path(kin, HOME, upright)


def test_linear_move_orientation_by_slerp(kin):
    start_pose = kin.fk(HOME)
    start_t = frames.pose_to_matrix(start_pose)
    turn = frames.rotvec_to_matrix([0.0, 0.0, 0.5]) @ frames.rotvec_to_matrix([0.3, 0.0, 0.0])
    target_t = start_t.copy()
    target_t[:3, :3] = turn @ start_t[:3, :3]
    target_t[:3, 3] += [-0.1, 0.1, 0.05]
    target = frames.matrix_to_pose(target_t)
    pts = linear_move(kin, HOME, target, 0.2, 1.0, 1.0)
    rel = frames.matrix_to_rotvec(turn)
    a, b = start_t[:3, 3], target_t[:3, 3]
    for pt in pts:
        pose = kin.fk(pt.positions)
        dist, s = _distance_to_segment(np.array(pose[:3]), a, b)
        assert dist < 0.0005
        expected = frames.rotvec_to_matrix(rel * s) @ start_t[:3, :3]
        assert np.linalg.norm(frames.matrix_to_rotvec(frames.rotvec_to_matrix(pose[3:]) @ expected.T)) < 1e-3
    steps = [frames.pose_distance(kin.fk(x.positions), kin.fk(y.positions))[1] for x, y in zip(pts, pts[1:])]
    assert max(steps) <= MAX_STEP_ANGLE + 1e-6
    assert frames.pose_distance(kin.fk(pts[-1].positions), target)[1] < 1e-4


def test_linear_move_stretched_for_the_joint_speed_cap(kin):
    start_pose = kin.fk(HOME)
    target = list(start_pose)
    target[0] -= 0.15
    target[1] += 0.15
    fast = linear_move(kin, HOME, target, 0.25, 2.0, 3.0)
    slow = linear_move(kin, HOME, target, 0.25, 2.0, 0.15)
    assert max(abs(v) for pt in slow for v in pt.velocities) <= 0.15 + 1e-9
    for pt0, pt1 in zip(with_start(HOME, slow), slow):
        for tau in (0.25, 0.5, 0.75):
            assert np.max(np.abs(hermite(pt0, pt1, tau)[1])) <= 0.15 + 1e-9
    assert slow[-1].time_from_start > fast[-1].time_from_start * 1.2


def test_linear_move_refuses_unreachable_targets(kin):
    with pytest.raises(TrajectoryError, match="^pose unreachable: "):
        linear_move(kin, HOME, [1.5, 0.0, 0.4, 0.0, math.pi, 0.0], 0.2, 1.0, 1.0)
    # reachable at both ends, but the straight line between them leaves the workspace: through the column above
    # the base is fine for a 7-axis arm, so go around the back: far out on one side to far out on the other
    left, right = [0.0, 0.75, 0.5, 0.0, math.pi, 0.0], [0.0, -0.75, 0.5, 0.0, math.pi, 0.0]
    q_left = kin.ik(left, HOME)
    assert q_left is not None and kin.ik(right, HOME) is not None
    with pytest.raises(TrajectoryError, match="^(pose unreachable|joint limit|singularity): .*along the line"):
        linear_move(kin, q_left, right, 0.2, 1.0, 1.0)


def test_linear_move_refuses_a_line_through_the_unreachable_column(ur5):
    # UR5, tool pointing down: the wrist cannot come closer than ~0.11 m to the base axis, so the straight line
    # from one side to the other leaves the workspace, although both ends are reachable
    home = [0.0, -1.57, 1.57, -1.57, -1.57, 0.0]
    a, b = [0.3, 0.0, 0.3, 0.0, math.pi, 0.0], [-0.3, 0.0, 0.3, 0.0, math.pi, 0.0]
    qa = ur5.ik(a, home)
    assert qa is not None and ur5.ik(b, home) is not None
    with pytest.raises(TrajectoryError, match=r"^pose unreachable: the line leaves the arm's reach \d+ mm along the line"):
        linear_move(ur5, qa, b, 0.2, 1.0, 1.0)


def test_linear_move_refuses_a_joint_limit_crossing(kin):
    # turning the tool from pointing down to pointing up drives joint 6 into its limit
    start_pose = kin.fk(HOME)
    target = start_pose[:3] + [0.0, 0.0, 0.0]
    with pytest.raises(TrajectoryError, match=r"^joint limit: iiwa_joint_6 would pass its limit \(-120.0 deg\)"):
        linear_move(kin, HOME, target, 0.2, 1.0, 1.0)


def test_linear_move_refuses_a_wrist_singularity(ur5):
    # UR5 with the wrist nearly straight (wrist 2 at 0.02 rad); a 10 cm line through the singular pose at
    # constant orientation needs wrist 1 and 3 to swing half a turn
    q = [0.0, -1.5708, 1.5708, -1.5708, 0.02, 0.0]
    pose = ur5.fk(q)
    u = np.linalg.svd(ur5.jacobian(q))[0][:3, -1]
    d = u / np.linalg.norm(u)
    a = list(np.array(pose[:3]) - 0.05 * d) + pose[3:]
    b = list(np.array(pose[:3]) + 0.05 * d) + pose[3:]
    qa = ur5.ik(a, q)
    assert qa is not None and ur5.ik(b, q) is not None
    with pytest.raises(TrajectoryError, match="^singularity: wrist_._joint would turn .* deg within 5 mm"):
        linear_move(ur5, qa, b, 0.2, 1.0, 1.0)


def test_linear_move_no_motion_and_bad_input(kin):
    pts = linear_move(kin, HOME, kin.fk(HOME), 0.2, 1.0, 1.0)
    assert len(pts) == 1 and pts[0].positions == pytest.approx(HOME) and pts[0].velocities == [0.0] * 7
    with pytest.raises(TrajectoryError, match="TCP speed"):
        linear_move(kin, HOME, kin.fk(HOME), -1.0, 1.0, 1.0)
    with pytest.raises(TrajectoryError, match="target pose"):
        linear_move(kin, HOME, [0.5, 0.0, 0.5], 0.2, 1.0, 1.0)


# ---- jogging ------------------------------------------------------------------------------------------------
def test_jog_point():
    pt = jog_point([0.0, 1.0], [0.5, -1.0], 0.1)
    assert pt.positions == pytest.approx([0.05, 0.9]) and pt.velocities == [0.5, -1.0]
    assert pt.time_from_start == 0.1
    # at a limit: that joint stops there, the other goes on
    pt = jog_point([0.0, 1.0], [0.5, 1.0], 0.1, lower=[-1.0, -1.0], upper=[1.0, 1.05])
    assert pt.positions == pytest.approx([0.05, 1.05]) and pt.velocities == [0.5, 0.0]


def test_cartesian_jog_follows_the_twist(kin):
    twist = [0.2, 0.0, -0.1, 0.0, 0.0, 0.0]
    qd = jog_joint_velocities(kin, HOME, twist, 1.0)
    assert kin.tcp_velocity(HOME, qd) == pytest.approx(twist, abs=1e-9)
    # asked above the cap: scaled down, same direction
    qd = jog_joint_velocities(kin, HOME, [1.0, 1.0, 0.0, 0.0, 0.0, 0.0], 5.0, max_tcp_speed=0.245)
    v = np.array(kin.tcp_velocity(HOME, qd))
    assert np.linalg.norm(v[:3]) == pytest.approx(0.245, abs=1e-9)
    assert v[:3] / np.linalg.norm(v[:3]) == pytest.approx([math.sqrt(0.5), math.sqrt(0.5), 0.0], abs=1e-9)


def test_cartesian_jog_joint_speed_cap_keeps_the_direction(kin):
    twist = [0.0, 0.0, 0.0, 0.0, 0.0, 3.0]        # turn about the tool fast: the wrist cannot
    qd = jog_joint_velocities(kin, HOME, twist, 0.5)
    assert max(abs(v) for v in qd) == pytest.approx(0.5)
    v = np.array(kin.tcp_velocity(HOME, qd))
    assert v / np.linalg.norm(v) == pytest.approx([0, 0, 0, 0, 0, 1.0], abs=1e-6)


@pytest.mark.parametrize("q", [
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],             # stretched straight up: joints 1, 3, 5, 7 on one line
    [0.0, 0.01, 0.0, 0.01, 0.0, 0.01, 0.0],
    [0.3, 0.6, 0.0, -0.005, 0.0, 1.0, 0.0],           # elbow stretched
    [0.5, 0.004, 0.7, 0.0, -0.4, -0.003, 0.2],        # stretched again, the axial joints turned
])
def test_cartesian_jog_near_a_singularity_keeps_the_caps(kin, q):
    cap, max_joint = 0.245, 1.0
    u, sv, _ = np.linalg.svd(kin.jacobian(q))
    assert sv[-1] < 0.02                      # really (nearly) singular
    twists = []
    for axis in range(6):
        for sign in (1, -1):
            twist = [0.0] * 6
            twist[axis] = sign * (cap if axis < 3 else 1.0)
            twists.append(twist)
    # the worst direction: along the singular vector (what a plain pseudo-inverse answers with racing joints)
    worst = u[:, -1] / max(np.linalg.norm(u[:3, -1]) / cap, np.linalg.norm(u[3:, -1]) / 1.0)
    twists += [list(worst), list(-worst)]
    for twist in twists:
        qd = jog_joint_velocities(kin, q, twist, max_joint, max_tcp_speed=cap)
        assert kin.tcp_speed(q, qd) <= cap + 1e-9
        assert max(abs(v) for v in qd) <= max_joint + 1e-9
        # one streamed jog step really moves the TCP no faster than the cap
        nxt = jog_point(q, qd, 0.05)
        moved = np.linalg.norm(np.array(kin.fk(nxt.positions)[:3]) - kin.fk(q)[:3])
        assert moved <= cap * 0.05 * 1.01 + 1e-6


# ---- not iiwa-specific: the UR5 of the UR sim -----------------------------------------------------------------
def test_ur5_urdf_matches_the_ur_sim_kinematics(ur5):
    assert ur5.joint_names == ur_urdf.ARM_JOINTS
    flange = Kinematics.from_urdf(ur_urdf.urdf_text("gripper"), "base_link", "flange")
    rng = np.random.default_rng(5)
    for _ in range(20):
        q = [float(v) for v in rng.uniform(-math.pi, math.pi, 6)]
        for k, tcp in ((ur5, ur_urdf.VACUUM_TCP), (flange, (0, 0, 0, 0, 0, 0))):
            ours, theirs = k.fk(q), ur_kin.forward(q, tcp)
            dpos, dang = frames.pose_distance(ours, theirs)
            assert dpos < 1e-6 and dang < 1e-6
        assert np.allclose(ur5.jacobian(q), ur_kin.jacobian(q, ur_urdf.VACUUM_TCP), atol=1e-6)
        sol = ur5.ik(ur5.fk(q), [v + 0.1 for v in q])
        assert sol is not None and frames.pose_distance(ur5.fk(sol), ur5.fk(q))[0] < 1e-5
