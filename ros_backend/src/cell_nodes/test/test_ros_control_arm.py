"""The ros_control backend without ROS: RosControlArm and RosControlConnector against a fake of the arm's own driver
(a Transport that records what is sent and plays a kinematic arm), and the driver core (ManualDriver) on top of it,
so the motion-safety rules are shown to hold on this backend too."""
from __future__ import annotations

import copy
import math
import os
import threading
import time
from typing import Callable, Optional, Sequence

import pybullet_data
import pytest

from cell_nodes.manual import frames
from cell_nodes.manual.config import RosControlSpec, parse_manual, plan_arms
from cell_nodes.manual.driver import ManualDriver, Refused
from cell_nodes.manual.limits import TCP_SPEED_CAP, Limits
from cell_nodes.manual.ros_control import arm as arm_mod
from cell_nodes.manual.ros_control.arm import (ABORTED, JOG_HORIZON, PREEMPTED, SUCCEEDED, JointSample,
                                               RosControlArm, Unreachable, load_kinematics)
from cell_nodes.manual.ros_control.connector import RosControlConnector
from cell_nodes.manual.ros_control.trajectory import TrajectoryPoint

JOINTS = [f"iiwa_joint_{i}" for i in range(1, 8)]
HOME = [0.0, 0.5, 0.0, -1.4, 0.0, 1.2, 0.0]
SPEC = RosControlSpec(joint_states="/iiwa/joint_states", controller="/iiwa/ctrl", base_link="iiwa_link_0",
                      tip_link="iiwa_link_ee", robot_description="/iiwa/robot_description",
                      outputs={0: "/iiwa/vacuum/set"}, inputs={1: "/iiwa/vacuum/holding"})


def iiwa_urdf(tool: float = 0.06) -> str:
    with open(os.path.join(pybullet_data.getDataPath(), "kuka_iiwa/model.urdf")) as fh:
        text = fh.read().replace("lbr_iiwa_", "iiwa_")
    return text.replace("</robot>", f'<link name="iiwa_link_ee"/><joint name="iiwa_joint_ee" type="fixed">'
                                    f'<parent link="iiwa_link_7"/><child link="iiwa_link_ee"/>'
                                    f'<origin xyz="0 0 {tool}" rpy="0 0 0"/></joint></robot>')


class FakeDriver:
    """The arm's own ROS driver as the backend sees it: a kinematic arm publishing joint states in its own order,
    goals that finish at once (or as the test says), a recorded command stream."""

    def __init__(self, q: Sequence[float] = HOME, names: Sequence[str] = tuple(reversed(JOINTS))) -> None:
        self.names = tuple(names)
        self.q = dict(zip(JOINTS, q))
        self.ready = True
        self.publishing = True
        self.goals: list[tuple[list[str], list[TrajectoryPoint], float]] = []
        self.commands: list[object] = []        # streamed points and "hold"
        self.cancels = 0
        self.outputs: dict[int, bool] = {}
        self.urdf = iiwa_urdf()
        self.finish: Optional[Callable[[Callable[[int, int, str], None]], None]] = None
        self._lock = threading.Lock()

    def joint_state(self) -> Optional[JointSample]:
        if not self.publishing:
            return None
        return JointSample(self.names, tuple(self.q.get(n, 0.0) for n in self.names), (0.0,) * len(self.names),
                           time.monotonic())

    def controller_ready(self) -> bool:
        return self.ready

    def send_goal(self, names, points, path_tolerance, goal_time_tolerance, done) -> None:
        self.goals.append((list(names), list(points), path_tolerance))
        if self.finish is not None:
            self.finish(done)
            return
        self.q.update(zip(names, points[-1].positions))  # an ideal arm: there at once
        done(SUCCEEDED, 0, "")

    def cancel_goal(self) -> None:
        self.cancels += 1

    def stream(self, names, point) -> None:
        with self._lock:
            self.commands.append(point)

    def hold(self) -> None:
        with self._lock:
            self.commands.append("hold")

    def set_output(self, output: int, value: bool) -> None:
        self.outputs[output] = value

    def inputs(self) -> dict[int, bool]:
        return {1: self.outputs.get(0, False)}

    def robot_description(self) -> str:
        return self.urdf

    def close(self) -> None:
        pass


@pytest.fixture
def fake() -> FakeDriver:
    return FakeDriver()


def make_arm(fake: FakeDriver) -> RosControlArm:
    return RosControlConnector(SPEC, JOINTS, fake, max_joint_speed=1.0, state_timeout=0.2).receive("x")


# ---------------------------------------------------------------------------------------------- reading and connect
def test_reads_the_joints_in_the_groups_order_and_the_tcp_from_the_urdf(fake):
    arm = make_arm(fake)
    assert arm.getActualQ() == pytest.approx(HOME)  # the driver publishes them reversed
    assert arm.getRobotMode() == 7 and arm.getRuntimeState() == 2 and arm.isProgramRunning()
    pose = arm.getActualTCPPose()
    assert pose == pytest.approx(arm.kin.fk(HOME))
    assert 0.3 < pose[0] < 0.8 and abs(pose[1]) < 1e-9  # the tool in front of the base, in the x-z plane
    fake.ready = False
    assert arm.getRobotMode() == 100 and not arm.isProgramRunning()


def test_connect_waits_a_moment_for_the_controller(fake):
    """The joint states come before the action server's status: connected, the arm says RUNNING from the first
    reading (no CONTROLLER_NOT_RUNNING blip, an error alarm, at every connect); a controller that stays silent is
    reported as not running after the wait."""
    checks = []

    def controller_ready() -> bool:
        checks.append(time.monotonic())
        return len(checks) > 3  # the status arrives on the fourth look

    fake.controller_ready = controller_ready  # type: ignore[method-assign]
    arm = make_arm(fake)
    assert len(checks) == 4 and arm.getRobotMode() == 7
    fake.controller_ready = lambda: False  # type: ignore[method-assign]
    t0 = time.monotonic()
    arm = RosControlConnector(SPEC, JOINTS, fake, max_joint_speed=1.0, state_timeout=0.2,
                              controller_timeout=0.1).receive("x")
    assert 0.1 <= time.monotonic() - t0 < 0.5 and arm.getRobotMode() == 100


@pytest.mark.parametrize("change, message", [
    (lambda f: setattr(f, "publishing", False), "no joint states on /iiwa/joint_states"),
    (lambda f: setattr(f, "names", tuple(JOINTS[:6])), "does not carry joint iiwa_joint_7"),
    (lambda f: setattr(f, "urdf", "<robot name='x'><link"), "does not give the arm's kinematics"),
    (lambda f: setattr(f, "urdf", iiwa_urdf().replace("iiwa_link_ee", "tool0")), "iiwa_link_ee"),
])
def test_connect_says_what_does_not_match(fake, change, message):
    change(fake)
    with pytest.raises(Unreachable) as e:
        make_arm(fake)
    assert message in e.value.reason


def test_group_joints_must_be_the_urdf_chains():
    with pytest.raises(Unreachable, match="not the URDF's joints"):
        load_kinematics(SPEC, JOINTS[:6] + ["iiwa_joint_x"], iiwa_urdf())


# ---------------------------------------------------------------------------------------------- moves
def test_move_j_sends_one_trajectory_to_the_target_with_the_path_tolerance(fake):
    arm = make_arm(fake)
    target = [0.3, 0.6, -0.2, -1.2, 0.1, 1.0, 0.4]
    assert arm.moveJ(target, 0.5, 1.0, True)
    names, points, tol = fake.goals[-1]
    assert names == JOINTS and tol == SPEC.path_tolerance
    assert points[-1].positions == pytest.approx(target) and points[-1].velocities == pytest.approx([0.0] * 7)
    assert max(abs(v) for p in points for v in p.velocities) <= 0.5 + 1e-9
    assert arm.getAsyncOperationProgress() == -1 and arm.getMoveError() == ""


def test_move_j_outside_a_joint_limit_is_refused_before_anything_is_sent(fake):
    arm = make_arm(fake)
    with pytest.raises(Refused, match="iiwa_joint_2: target 2.500 rad is outside its limits"):
        arm.moveJ([0.0, 2.5, 0.0, -1.4, 0.0, 1.2, 0.0], 0.5, 1.0, True)
    assert fake.goals == []


def test_an_aborted_goal_is_a_move_error_and_our_own_stop_is_not(fake):
    arm = make_arm(fake)
    pending: list[Callable[[int, int, str], None]] = []
    fake.finish = pending.append
    arm.moveJ([0.2] + HOME[1:], 0.5, 1.0, True)
    assert arm.getAsyncOperationProgress() == 0
    pending.pop()(ABORTED, -4, "iiwa_joint_3 lags 0.12 rad")
    assert arm.getAsyncOperationProgress() == -1
    assert arm.getMoveError() == ("the controller aborted the trajectory: PATH_TOLERANCE_VIOLATED "
                                  "(iiwa_joint_3 lags 0.12 rad)")
    arm.moveJ([0.3] + HOME[1:], 0.5, 1.0, True)
    assert arm.getMoveError() == ""  # a new goal starts clean
    arm.stopJ(2.0, True)
    assert fake.cancels == 1 and fake.commands[-1] == "hold"
    pending.pop()(PREEMPTED, 0, "")   # the cancelled goal's result arrives late
    assert arm.getMoveError() == "" and arm.getAsyncOperationProgress() == -1
    # Preempted by someone else (another client's goal or command): a fault, named as such.
    arm.moveJ([0.4] + HOME[1:], 0.5, 1.0, True)
    pending.pop()(PREEMPTED, 0, "")
    assert arm.getMoveError().startswith("the trajectory was preempted: another client")


def test_move_l_is_a_straight_line_and_an_unreachable_pose_is_refused(fake):
    arm = make_arm(fake)
    start = arm.getActualTCPPose()
    target = list(start)
    target[2] += 0.05
    arm.moveL(target, 0.25, 1.0, True)
    assert arm.getActualTCPPose()[:3] == pytest.approx(target[:3], abs=1e-5)
    far = list(start)
    far[0] = 2.0
    assert not arm.getInverseKinematicsHasSolution(far, HOME)
    with pytest.raises(Refused, match="unreachable"):
        arm.moveL(far, 0.25, 1.0, True)
    assert len(fake.goals) == 1


def test_a_stopped_controller_refuses_moves_and_jogs(fake):
    arm = make_arm(fake)
    fake.ready = False
    with pytest.raises(Refused, match="not running"):
        arm.moveJ(HOME, 0.5, 1.0, True)
    with pytest.raises(Refused, match="not running"):
        arm.speedJ([0.1] + [0.0] * 6, 1.0, 0.0)


# ---------------------------------------------------------------------------------------------- jogs
def wait_for(predicate, timeout=10.0):
    deadline = time.monotonic() + timeout
    while not predicate():
        # A jog stream that died says so at once (its thread's name), rather than as a timeout.
        assert time.monotonic() < deadline, f"timed out; threads: {sorted(t.name for t in threading.enumerate())}"
        time.sleep(0.005)


def test_a_joint_jog_streams_points_ahead_and_stop_holds_last(fake):
    arm = make_arm(fake)
    arm.speedJ([0.2, 0, 0, 0, 0, 0, 0], 1.0, 0.0)
    # It ramps up at the command's acceleration (1 rad/s^2: 0.2 s), never jumping to full speed.
    wait_for(lambda: len(fake.commands) >= 2)
    assert fake.commands[0].velocities[0] < 0.05
    wait_for(lambda: fake.commands[-1].velocities[0] == pytest.approx(0.2 * arm_mod.STREAM_SPEED_FACTOR))
    p = fake.commands[-1]
    assert p.time_from_start == pytest.approx(JOG_HORIZON) and p.velocities[0] == pytest.approx(0.2 * arm_mod.STREAM_SPEED_FACTOR)
    assert p.positions[0] > HOME[0] + 0.2 * JOG_HORIZON - 1e-9  # ahead of the arm by the horizon
    arm.speedJ([-0.2, 0, 0, 0, 0, 0, 0], 1.0, 0.0)  # a new speed replaces the stream's (no second stream)
    wait_for(lambda: fake.commands[-1] != "hold" and fake.commands[-1].velocities[0] < 0)
    assert sum(t.name == "ros-control-jog" for t in threading.enumerate()) == 1
    arm.speedStop(10.0)
    n = len(fake.commands)
    assert fake.commands[-1] == "hold"
    time.sleep(5 * arm_mod.STREAM_PERIOD)  # a stream that went on would have added points by now
    assert len(fake.commands) == n


def test_a_cartesian_jog_keeps_the_tcp_under_the_cap(fake):
    arm = make_arm(fake)
    arm.speedL([0.0, 0.0, 0.3, 0.0, 0.0, 0.0], 1.0, 0.0)  # asks more than the cap: the stream scales it down
    wait_for(lambda: len(fake.commands) >= 3)
    arm.speedStop()
    for p in fake.commands[:-1]:
        assert arm.kin.tcp_speed(p.positions, p.velocities) <= TCP_SPEED_CAP + 1e-9


def test_a_jog_stops_at_a_joint_limit(fake):
    lo = -2.96  # iiwa joint 1
    fake.q["iiwa_joint_1"] = lo + 0.1
    arm = make_arm(fake)
    arm.speedJ([-1.0, 0, 0, 0, 0, 0, 0], 10.0, 0.0)
    wait_for(lambda: any(p.velocities[0] < -0.05 for p in fake.commands))  # it did move towards the limit
    wait_for(lambda: fake.commands[-1].velocities[0] == 0.0)                 # and stopped before it
    arm.speedStop()
    assert all(p.positions[0] > lo for p in fake.commands[:-1])
    assert fake.commands[-2].velocities[0] == 0.0


def test_io_goes_to_the_wired_services_and_unwired_is_refused(fake):
    arm = make_arm(fake)
    arm.setStandardDigitalOut(0, True)
    assert fake.outputs == {0: True} and arm.getActualDigitalOutputBits() == 1
    assert arm.getActualDigitalInputBits() == 0b10
    with pytest.raises(Refused, match="digital output 3 is not wired"):
        arm.setStandardDigitalOut(3, True)


# ---------------------------------------------------------------------------------------------- the driver core on it
SECTION = {"groups": [{"name": "arm", "joints": JOINTS, "driver": "ros_control", "configurations": {"home": HOME,
                       "ready": [0.3, 0.6, -0.2, -1.2, 0.1, 1.0, 0.4]},
                       "ros_control": {"joint_states": "/iiwa/joint_states", "controller": "/iiwa/ctrl",
                                       "robot_description": "/iiwa/robot_description", "base_link": "iiwa_link_0",
                                       "tip_link": "iiwa_link_ee", "io": {"outputs": {0: "/iiwa/vacuum/set"},
                                                                          "inputs": {1: "/iiwa/vacuum/holding"}}}}],
           "tools": [{"name": "vacuum", "actions": [{"name": "on", "steps": [{"digital_out": 0, "value": True},
                                                                              {"wait_input": 1, "value": True}]}]}]}


def start_driver(fake: FakeDriver, section: dict = SECTION) -> ManualDriver:
    config = parse_manual(section)
    (arm,) = plan_arms(config, {})
    assert arm.ros_control is not None and arm.joint_names == tuple(JOINTS)
    limits = Limits.from_section(config.limits, 0.2)
    d = ManualDriver(arm.config(config), arm.ros_control.controller,
                     RosControlConnector(arm.ros_control, arm.joint_names, fake, limits.max_speed, state_timeout=0.2),
                     limits, joint_names=arm.joint_names, poll_rate=100.0, retry_s=0.1)
    d.start()
    wait_for(lambda: d.connected and d.snapshot().robot_mode == "RUNNING")  # connected, and polled once
    return d


@pytest.fixture
def driver(fake):
    d = start_driver(fake)
    yield d
    d.shutdown()


def test_the_driver_core_moves_and_runs_tools_on_this_backend(driver, fake):
    ok, message = driver.move_named("arm", "ready")
    assert ok, message
    assert [fake.q[j] for j in JOINTS] == pytest.approx(SECTION["groups"][0]["configurations"]["ready"])
    ok, message = driver.tool_action("vacuum", "on")
    assert ok, message
    assert fake.outputs == {0: True}


def test_an_aborted_trajectory_fails_the_move_and_is_the_arms_fault_until_the_next_command(driver, fake):
    fake.finish = lambda done: done(ABORTED, -4, "iiwa_joint_2 lags")
    ok, message = driver.move_named("arm", "ready")
    assert not ok and "PATH_TOLERANCE_VIOLATED" in message
    assert "PATH_TOLERANCE_VIOLATED" in driver.state().fault
    fake.finish = None
    assert driver.move_named("arm", "home")[0]
    assert driver.state().fault == ""


def test_a_jog_without_heartbeats_is_stopped_by_the_watchdog(driver, fake):
    driver.jog("arm", "joint", 0, 1, 0.5)
    wait_for(lambda: driver.state().motion == "jogging")
    wait_for(lambda: fake.commands and fake.commands[-1] == "hold", timeout=1.0)  # 0.2 s without a heartbeat
    assert "no heartbeat" in driver.state().message


def test_the_driver_refuses_when_joint_states_stop(driver, fake):
    fake.publishing = False
    wait_for(lambda: not driver.connected, timeout=3.0)
    ok, message = driver.move_named("arm", "home")
    assert not ok and "unreachable" in message
    # The reconnection attempts say why.
    wait_for(lambda: "no joint states on /iiwa/joint_states" in driver.state().message, timeout=3.0)


# ---------------------------------------------------------------------------------------------- the move preview on it
READY = SECTION["groups"][0]["configurations"]["ready"]


def q_of(fake: FakeDriver) -> list[float]:
    return [fake.q[j] for j in JOINTS]


def test_the_preview_of_a_relative_move_is_where_the_move_ends(driver, fake):
    """Same start, same planning (trajectory.linear_path, the waypoints' IK): the previewed joints are the last point
    of the trajectory the move then sends, and where the arm ends."""
    kin = load_kinematics(SPEC, JOINTS, iiwa_urdf())
    offset = [0.0, 0.05, -0.05, 0.0, 0.0, 0.2]
    start = q_of(fake)
    ok, message, names, q, tcp = driver.preview_move("arm", "relative", offset=offset, frame="tool")
    assert (ok, message, names) == (True, "the relative target is reachable", JOINTS)
    d, a = frames.pose_distance(tcp, frames.relative_target(kin.fk(start), offset, "tool"))
    assert d < 1e-9 and a < 1e-9                    # the relative target from the current TCP pose
    d, a = frames.pose_distance(kin.fk(q), tcp)
    assert d < 1e-5 and a < 1e-4                    # the joints reach it
    assert fake.goals == [] and driver.state().motion == "idle"
    assert driver.move_relative("arm", offset, "tool") == (True, "arrived at the relative target")
    (_, points, _), = fake.goals
    assert points[-1].positions == pytest.approx(q, abs=1e-9)
    assert q_of(fake) == pytest.approx(q, abs=1e-9)


def test_the_preview_of_a_named_configuration_and_of_a_pose(driver, fake):
    kin = load_kinematics(SPEC, JOINTS, iiwa_urdf())
    ok, message, names, q, tcp = driver.preview_move("arm", "named", "ready")
    assert (ok, message, names, q) == (True, "ready is reachable", JOINTS, READY)
    assert tcp == pytest.approx(kin.fk(READY))
    pose = kin.fk([0.2, 0.6, 0.0, -1.2, 0.0, 1.1, 0.0])
    ok, message, _, q, tcp = driver.preview_move("arm", "pose", pose=pose)
    assert (ok, message, tcp) == (True, "the pose target is reachable", pose)
    assert driver.move_pose("arm", pose) == (True, "arrived at the pose target")
    assert q_of(fake) == pytest.approx(q, abs=1e-9)


def test_a_target_out_of_reach_or_limits_is_refused_with_the_moves_own_words(fake):
    section = copy.deepcopy(SECTION)
    section["groups"][0]["configurations"]["stretched"] = [0.0, 2.5, 0.0, -1.4, 0.0, 1.2, 0.0]
    d = start_driver(fake, section)
    try:
        # a joint target outside the URDF's limits: the backend's own moveJ check, named by the joint
        preview = d.preview_move("arm", "named", "stretched")
        assert preview[0] is False and preview[1].startswith("joint iiwa_joint_2: target 2.500 rad is outside its "
                                                              "limits")
        assert d.move_named("arm", "stretched") == (False, preview[1])
        # no IK solution at all
        far = [2.0, 0.0, 0.4, 0.0, math.pi, 0.0]
        assert d.preview_move("arm", "pose", pose=far) == (False, "pose unreachable: no inverse kinematics solution",
                                                            [], [], [])
        assert d.move_pose("arm", far) == (False, "pose unreachable: no inverse kinematics solution")
        # reachable as a pose, but the straight line there drives joint 6 into its limit: the linear move's planning
        upright = d.snapshot().tcp_pose[:3] + (0.0, 0.0, 0.0)
        preview = d.preview_move("arm", "pose", pose=upright)
        assert preview[0] is False and preview[1].startswith("joint limit: iiwa_joint_6 would pass its limit")
        assert d.move_pose("arm", upright) == (False, preview[1])
        assert fake.goals == [] and d.state().motion == "idle"
    finally:
        d.shutdown()


def test_the_preview_answers_while_a_move_runs(driver, fake):
    pending: list[Callable[[int, int, str], None]] = []
    fake.finish = pending.append   # the goal stays active until the test ends it
    result: dict = {}
    mover = threading.Thread(target=lambda: result.setdefault("r", driver.move_named("arm", "ready")))
    mover.start()
    wait_for(lambda: pending)
    ok, message, _, q, _ = driver.preview_move("arm", "relative", offset=[0, 0, 0.03, 0, 0, 0], frame="base")
    assert ok, message
    assert driver.preview_move("arm", "named", "home")[:4] == (True, "home is reachable", JOINTS, HOME)
    s = driver.state()
    assert (s.motion, s.motion_target) == ("moving", "ready") and len(fake.goals) == 1 and fake.cancels == 0
    fake.q.update(zip(JOINTS, READY))
    pending.pop()(SUCCEEDED, 0, "")
    mover.join(5)
    assert result["r"] == (True, "arrived at ready")
