"""The ros_control cell (sim/ros_control) as a process under a live roscore: the simulated driver's ROS interface
(FollowJointTrajectory action, command topic, /joint_states, robot_description, IO) with the names of the test cell
cells/iiwa-test.yaml (other names than config/iiwa-cell.yaml: nothing may be hard-coded), the faults, the physics.

Arm poses used (cup pointing straight down, TCP in the base frame = world frame):
START  (0.55, 0, 0.30)   ABOVE (0.55, 0, 0.10) over cube 3 at (0.55, 0.0)
TOUCH  (0.55, 0, 0.042): the cup face 2 mm above the cube's top (0.04)   LIFTED (0.55, 0, 0.15)
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import actionlib
import numpy as np
import pytest
import rosgraph
import rospy
from actionlib_msgs.msg import GoalStatus
from cell_msgs.msg import AlarmList
from cell_msgs.srv import TriggerFault
from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryGoal, FollowJointTrajectoryResult
from geometry_msgs.msg import PoseArray, WrenchStamped
from sensor_msgs.msg import CompressedImage, JointState
from std_msgs.msg import Bool
from std_srvs.srv import SetBool
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import MarkerArray

from conftest import wait_for  # the repository's conftest (it also gives the roscore fixture)
from sim.tests.conftest import SimProcess

CELL = Path(__file__).resolve().parent / "cells" / "iiwa-test.yaml"
JOINTS = [f"r7_joint_{i}" for i in range(1, 8)]
NS = "/r7/arm_controller"
START = [0.0, 0.5591, 0.0, -1.6245, 0.0, 0.958, 0.0]
ABOVE = [0.0, 0.9033, 0.0, -1.6555, 0.0, 0.5828, 0.0]
TOUCH = [0.0, 1.022, 0.0, -1.6199, 0.0, 0.4997, 0.0]
LIFTED = [0.0, 0.8063, 0.0, -1.6701, 0.0, 0.6652, 0.0]
R = FollowJointTrajectoryResult


class Latest:
    """The last message on a topic, its arrival times, and a way to wait for a condition on new messages."""

    def __init__(self, topic: str, mtype) -> None:
        self.msg = None
        self.times: list[float] = []
        self.cond = threading.Condition()
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=100)

    def _cb(self, msg) -> None:
        with self.cond:
            self.msg = msg
            self.times.append(time.monotonic())
            self.cond.notify_all()

    def wait(self, predicate, timeout: float, what: str):
        deadline = time.monotonic() + timeout
        with self.cond:
            while self.msg is None or not predicate(self.msg):
                left = deadline - time.monotonic()
                if left <= 0:
                    raise AssertionError(f"timed out after {timeout}s waiting for {what}; last: {self.msg}")
                self.cond.wait(left)
            return self.msg

    def rate(self) -> float:
        t = self.times[-50:]
        return (len(t) - 1) / (t[-1] - t[0]) if len(t) > 2 else 0.0


@pytest.fixture(scope="module")
def iiwa(roscore):
    env = dict(os.environ, ROS_MASTER_URI=roscore)
    env.pop("CELL_CONFIG", None)
    sim = SimProcess("127.0.0.1", ["--cell", str(CELL), "--camera-size", "160x120", "--camera-rate", "5"], env)
    if not rospy.core.is_initialized():
        rospy.init_node("sim_test", anonymous=True, disable_signals=True)
    client = actionlib.ActionClient(f"{NS}/follow_joint_trajectory", FollowJointTrajectoryAction)
    simple = actionlib.SimpleActionClient(f"{NS}/follow_joint_trajectory", FollowJointTrajectoryAction)
    if not simple.wait_for_server(rospy.Duration(30)):
        raise AssertionError(f"no action server:\n{sim.output()}")
    joints = Latest("/r7/joint_states", JointState)
    joints.wait(lambda m: True, 10, "joint states")
    yield sim, simple, client, joints
    took = sim.stop()
    assert took < 2.0, f"the ros_control sim took {took:.2f}s to exit on SIGTERM"
    assert "Traceback" not in sim.output(), sim.output()[-3000:]


def goal(q, duration: float, names=JOINTS, **kw) -> FollowJointTrajectoryGoal:
    """One cubic segment to q (zero velocity at the end), joint names in the order given."""
    order = [JOINTS.index(n) for n in names]
    point = JointTrajectoryPoint(positions=[q[i] for i in order], velocities=[0.0] * len(names),
                                 time_from_start=rospy.Duration(duration))
    return FollowJointTrajectoryGoal(trajectory=JointTrajectory(joint_names=list(names), points=[point]), **kw)


def move(simple, q, duration: float = 1.0):
    simple.send_goal(goal(q, duration))
    assert simple.wait_for_result(rospy.Duration(duration + 10)), "no result"
    result = simple.get_result()
    assert simple.get_state() == GoalStatus.SUCCEEDED and result.error_code == R.SUCCESSFUL, result
    return result


def error(js: JointState, q) -> float:
    pos = dict(zip(js.name, js.position))
    return max(abs(pos[n] - v) for n, v in zip(JOINTS, q))


def fault(name: str):
    rospy.wait_for_service("/sim/trigger_fault", 5)
    return rospy.ServiceProxy("/sim/trigger_fault", TriggerFault)(name)


def test_the_driver_interface_is_published_under_the_cell_files_names(iiwa):
    sim, simple, client, joints = iiwa
    js = joints.wait(lambda m: True, 5, "joint states")
    assert list(js.name) == JOINTS and len(js.position) == len(js.velocity) == len(js.effort) == 7
    wait_for(lambda: len(joints.times) > 60, 5, what="60 joint states")
    assert 80 <= joints.rate() <= 115, f"/joint_states at {joints.rate():.1f} Hz, rate_hz 100"
    urdf = rospy.get_param("/r7/robot_description")
    for name in ["r7_link_0", "r7_cup_face", "r7_link_ft", *JOINTS]:
        assert f'name="{name}"' in urdf
    assert "lbr_iiwa_" not in urdf and 'velocity="10"' in urdf and "file://" in urdf
    held = Latest("/r7/io/part_held", Bool)
    held.wait(lambda m: True, 5, "the part-held input")
    wait_for(lambda: len(held.times) > 12, 5, what="part-held messages")
    assert held.rate() >= 10
    wrench = Latest("/r7/wrench", WrenchStamped).wait(lambda m: True, 5, "the wrist wrench")
    assert wrench.header.frame_id == "r7_link_ft" and abs(wrench.wrench.force.z) > 1  # the tool's weight
    objects = Latest("/sim/objects", PoseArray).wait(lambda m: len(m.poses) == 3, 5, "the parts")
    assert objects.header.frame_id == "base"
    assert [round(p.position.y, 3) for p in objects.poses] == [-0.2, -0.1, 0.0]
    assert all(abs(p.position.z - 0.02) < 0.001 for p in objects.poses)
    # The cell file's scene.markers: the parts (frame world) and the fixture's plate and pocket walls.
    markers = Latest("/r7/scene/parts", MarkerArray).wait(lambda m: True, 5, "the scene markers")
    parts = [m for m in markers.markers if m.ns == "parts"]
    assert [round(m.pose.position.y, 3) for m in parts] == [-0.2, -0.1, 0.0] and [m.id for m in parts] == [0, 1, 2]
    assert all(m.header.frame_id == "world" and m.type == m.CUBE and m.scale.x == 0.04 for m in parts)
    assert [m.text for m in markers.markers if m.ns == "stations"] == ["output"] * 13  # plate + 4 walls x 3 pockets
    faults = Latest("/sim/faults", AlarmList).wait(lambda m: True, 5, "the latched faults")
    assert {a.id for a in faults.alarms} == {"collision", "vacuum_fault"} and not any(a.active for a in faults.alarms)
    image = Latest("/r7/camera/overview/compressed", CompressedImage).wait(lambda m: True, 30, "a camera frame")
    assert bytes(image.data[:2]) == b"\xff\xd8" and image.header.frame_id == "camera_overview"


def test_a_goal_brings_the_arm_within_5_mrad_on_every_joint(iiwa):
    sim, simple, client, joints = iiwa
    move(simple, START, 0.6)
    # names in another order than the controller's: mapped by name
    shuffled = list(reversed(JOINTS))
    target = [0.3, 0.7, -0.2, -1.3, 0.25, 0.9, 0.4]
    simple.send_goal(goal(target, 1.2, shuffled))
    assert simple.wait_for_result(rospy.Duration(10))
    assert simple.get_state() == GoalStatus.SUCCEEDED and simple.get_result().error_code == R.SUCCESSFUL
    joints.wait(lambda m: error(m, target) < 0.005, 2, "the arm within 0.005 rad of the goal")


def test_wrong_joints_and_bad_times_are_rejected_with_their_error_codes(iiwa):
    sim, simple, client, joints = iiwa
    names = JOINTS[:6] + ["iiwa_joint_7"]
    simple.send_goal(goal(START, 1.0, JOINTS))  # fine, then a bad one with the wrong names
    bad = goal(START, 1.0)
    bad.trajectory.joint_names = names
    simple.send_goal(bad)
    assert simple.wait_for_result(rospy.Duration(5))
    assert simple.get_state() == GoalStatus.REJECTED
    assert simple.get_result().error_code == R.INVALID_JOINTS and "iiwa_joint_7" in simple.get_result().error_string
    bad = goal(START, 1.0)
    bad.trajectory.points.append(JointTrajectoryPoint(positions=START, time_from_start=rospy.Duration(0.5)))
    simple.send_goal(bad)
    assert simple.wait_for_result(rospy.Duration(5))
    assert simple.get_state() == GoalStatus.REJECTED and simple.get_result().error_code == R.INVALID_GOAL


def test_collision_aborts_the_goal_with_path_tolerance_violated_until_reset(iiwa):
    sim, simple, client, joints = iiwa
    move(simple, START, 0.6)
    faults = Latest("/sim/faults", AlarmList)
    target = [0.8, 0.8, 0.0, -1.2, 0.0, 0.9, 0.0]
    simple.send_goal(goal(target, 2.0))
    joints.wait(lambda m: error(m, START) > 0.05, 3, "the arm to start moving")
    assert fault("collision").success
    faults.wait(lambda m: any(a.id == "collision" and a.active for a in m.alarms), 3, "collision active")
    assert simple.wait_for_result(rospy.Duration(5))
    result = simple.get_result()
    assert simple.get_state() == GoalStatus.ABORTED and result.error_code == R.PATH_TOLERANCE_VIOLATED
    assert "r7_joint_" in result.error_string and "tolerance" in result.error_string
    stuck = list(joints.wait(lambda m: max(map(abs, m.velocity)) < 0.01, 2, "the blocked arm still").position)
    # still blocked: a new goal cannot move it either
    simple.send_goal(goal(target, 1.0))
    assert simple.wait_for_result(rospy.Duration(5))
    assert simple.get_result().error_code == R.PATH_TOLERANCE_VIOLATED
    assert error(joints.msg, stuck) < 0.01
    assert fault("reset").success
    faults.wait(lambda m: not any(a.active for a in m.alarms), 3, "no active fault")
    move(simple, START, 1.0)
    joints.wait(lambda m: error(m, START) < 0.005, 2, "the arm back at the start")


def test_a_new_goal_preempts_and_a_cancel_holds(iiwa):
    sim, simple, client, joints = iiwa
    move(simple, START, 0.6)
    first = client.send_goal(goal(ABOVE, 3.0))
    joints.wait(lambda m: error(m, START) > 0.03, 3, "the arm to start moving")
    second = client.send_goal(goal(START, 0.8))
    wait_for(lambda: first.get_goal_status() == GoalStatus.PREEMPTED, 3, what="the first goal preempted")
    wait_for(lambda: second.get_goal_status() == GoalStatus.SUCCEEDED, 5, what="the second goal done")
    third = client.send_goal(goal(ABOVE, 3.0))
    joints.wait(lambda m: error(m, START) > 0.03, 3, "the arm to start moving")
    third.cancel()
    wait_for(lambda: third.get_goal_status() == GoalStatus.PREEMPTED, 3, what="the canceled goal preempted")
    t0 = time.monotonic()
    joints.wait(lambda m: time.monotonic() - t0 > 0.3 and max(map(abs, m.velocity)) < 0.01, 3, "the arm held")


def test_the_command_topic_moves_the_arm_and_an_empty_trajectory_stops_it(iiwa):
    sim, simple, client, joints = iiwa
    move(simple, START, 0.6)
    pub = rospy.Publisher(f"{NS}/command", JointTrajectory, queue_size=5)
    wait_for(lambda: pub.get_num_connections() > 0, 5, what="the command topic's subscriber")
    # an action goal running is preempted by a command
    running = client.send_goal(goal(ABOVE, 4.0))
    wait_for(lambda: running.get_goal_status() == GoalStatus.ACTIVE, 3, what="the goal active")
    target = [0.6, 0.5591, 0.0, -1.6245, 0.0, 0.958, 0.0]
    pub.publish(JointTrajectory(joint_names=JOINTS, points=[
        JointTrajectoryPoint(positions=target, velocities=[0.0] * 7, time_from_start=rospy.Duration(2.0))]))
    wait_for(lambda: running.get_goal_status() == GoalStatus.PREEMPTED, 3, what="the goal preempted by the command")
    joints.wait(lambda m: m.position[0] > 0.15 and abs(m.velocity[0]) > 0.2, 3, "joint 1 past 0.15 rad, moving")
    pub.publish(JointTrajectory(joint_names=JOINTS))
    t_stop = time.monotonic()
    still = joints.wait(lambda m: max(map(abs, m.velocity)) < 0.01, 1.0, "every joint below 0.01 rad/s")
    took = time.monotonic() - t_stop
    assert took < 0.3, f"stopped after {took:.2f}s"
    # and it stays there
    time_stopped = time.monotonic()
    joints.wait(lambda m: time.monotonic() - time_stopped > 0.5, 2, "0.5 s more")
    assert error(joints.msg, list(still.position)) < 0.005 and max(map(abs, joints.msg.velocity)) < 0.01
    assert 0.15 < joints.msg.position[0] < 0.55  # stopped on the way


def test_the_vacuum_holds_and_carries_a_cube(iiwa):
    sim, simple, client, joints = iiwa
    suction = rospy.ServiceProxy("/r7/io/suction", SetBool)
    held = Latest("/r7/io/part_held", Bool)
    objects = Latest("/sim/objects", PoseArray)
    move(simple, START, 0.6)
    assert suction(False).success
    move(simple, ABOVE, 1.0)
    move(simple, TOUCH, 0.8)
    assert held.wait(lambda m: True, 2, "part held").data is False
    assert suction(True).success
    held.wait(lambda m: m.data, 2, "the part-held input true")
    move(simple, LIFTED, 1.0)
    cube = objects.wait(lambda m: m.poses[2].position.z > 0.12, 3, "cube 3 lifted").poses[2].position
    assert abs(cube.x - 0.55) < 0.005 and abs(cube.y) < 0.005  # centred under the cup
    assert abs(objects.msg.poses[1].position.z - 0.02) < 0.001  # its neighbour stayed
    assert held.msg.data
    assert suction(False).success
    held.wait(lambda m: not m.data, 2, "the part-held input false")
    objects.wait(lambda m: m.poses[2].position.z < 0.021, 3, "cube 3 back on the table")


def test_without_a_master_it_runs_and_stops_on_sigterm(tmp_path):
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:1")
    env.pop("CELL_CONFIG", None)
    sim = SimProcess("127.0.0.1", ["--cell", str(CELL), "--no-cameras"], env)
    wait_for(lambda: "cell running" in sim.output() or sim.proc.poll() is not None, 20, what="the sim running")
    assert "ROS master not reachable" in sim.output()
    assert sim.stop(signal.SIGINT) < 2.0
    assert sim.proc.returncode == 0 and "Traceback" not in sim.output()


@pytest.mark.parametrize("old, new, expected", [
    ("start_joints: [0.0, 0.5591,", "start_joints: [0.5591,", "simulation.arms[0].start_joints: expected 7 joint positions"),
    ("kind: ros_control", "kind: ros_kontrol", "simulation.kind: expected ur or ros_control, got 'ros_kontrol'"),
    ("tip_link: r7_cup_face", "tip_link: r7_link_7", "manual.groups[arm].ros_control.tip_link: expected the name"),
    ("inputs: { 3:", "inputs: { 4:", "manual.groups[arm].ros_control.io.inputs: no input 3"),
    ("rename: { lbr_iiwa_: r7_ }", "rename: { lbr_iiwa_: iiwa_ }", "manual.groups[arm].joints: the simulated model's"),
], ids=["start-joints", "kind", "tip-link", "io", "rename"])
def test_an_unusable_simulation_section_exits_2_with_one_line(tmp_path, old, new, expected):
    bad = tmp_path / "bad.yaml"
    assert old in CELL.read_text()
    bad.write_text(CELL.read_text().replace(old, new))
    out = subprocess.run([sys.executable, "-m", "sim", "--cell", str(bad)], capture_output=True, text=True,
                         cwd=Path(__file__).resolve().parents[2], timeout=30)
    assert out.returncode == 2, out.stderr
    lines = [ln for ln in out.stderr.splitlines() if not ln.startswith("pybullet build time")]  # pybullet's banner
    assert len(lines) == 1 and lines[0].startswith("python -m sim: cell file ") and expected in lines[0], out.stderr
