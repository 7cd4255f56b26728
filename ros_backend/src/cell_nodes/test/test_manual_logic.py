"""Manual motion, the plain-Python logic (no ROS, no controller): limits and clamping, frames, the jog supervisor
with a fake clock, the cell file section, and the driver core against a fake controller (refusals, clamped
moves, jog heartbeat, stop, tool steps, reconnection)."""
from __future__ import annotations

import math
import threading
import time
from pathlib import Path
import logging
from typing import Any, Optional

import numpy as np
import pytest
import yaml

from cell_nodes.manual import frames
from cell_nodes.manual.cell_driver import CellDriver
from cell_nodes.manual.config import (UR_JOINTS, ConfigError, DigitalOut, MoveNamedStep, Wait, WaitInput, parse_manual,
                                      plan_arms, resolve_hosts, ur_joint_index)
from cell_nodes.manual.controller import CallTimeout, ClientGone, Gate, Guarded, fk_lever
from cell_nodes.manual.driver import DriverState, ManualDriver, Snapshot
from cell_nodes.manual.jog import Decision, Jog, JogSupervisor
from cell_nodes.manual.limits import (STOP_DECEL_JOINT, STOP_DECEL_TCP, TCP_COMMAND_MARGIN, TCP_SPEED_CAP,
                                      WATCHDOG_DECEL_JOINT, Limits)

CAP = TCP_SPEED_CAP * TCP_COMMAND_MARGIN  # the highest TCP speed ever commanded
from conftest import wait_for
from said_check import check_said
from cell_nodes.said import say

DEMO = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"
HOME = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]


def demo_section() -> dict:
    return yaml.safe_load(DEMO.read_text())["manual"]


# ---------------------------------------------------------------------------------------------- limits
def test_tcp_speed_is_capped_at_250_mm_s_whatever_the_cell_file_says() -> None:
    assert Limits.from_section({"max_tcp_speed": 1.0}).max_tcp_speed == TCP_SPEED_CAP == 0.25
    assert Limits.from_section({}).max_tcp_speed == 0.25
    assert 0.24 <= CAP < 0.25  # commands keep a small margin: the measured speed must stay under the cap
    lim = Limits.from_section({"max_tcp_speed": 0.1})
    assert lim.max_tcp_speed == 0.1
    assert lim.tcp_speed(5.0) == pytest.approx(0.1 * TCP_COMMAND_MARGIN) and lim.tcp_speed(0.05) == 0.05
    loose = Limits.from_section({"max_tcp_speed": 3.0, "max_speed": 2.0})
    assert loose.tcp_speed(3.0) == CAP
    assert loose.cartesian_jog_speed(0, 1.0) == CAP  # X at full slider
    assert loose.cartesian_jog_speed(2, 5.0) == CAP  # a slider above 1 is clamped to 1
    assert loose.cartesian_jog_speed(5, 0.5) == 1.0   # RZ: rad/s, half of max_speed


def test_zero_means_default_and_maxima_clamp() -> None:
    lim = Limits.from_section(demo_section())
    assert (lim.default_speed, lim.max_speed, lim.max_acceleration) == (0.25, 1.0, 1.5)
    assert lim.joint_speed(0) == 0.25 and lim.joint_speed(-1) == 0.25 and lim.joint_speed(math.nan) == 0.25
    assert lim.joint_speed(0.5) == 0.5 and lim.joint_speed(9.0) == 1.0
    assert lim.joint_acceleration(0) == 0.5 and lim.joint_acceleration(99) == 1.5
    assert lim.tcp_speed(0) == 0.1 and lim.tcp_acceleration(0) == 0.5 and lim.tcp_acceleration(50) == 1.0
    # defaults never above the maxima
    assert Limits.from_section({"default_speed": 2.0, "max_speed": 0.5}).default_speed == 0.5


def test_jog_speed_fraction_and_joint_jog_tcp_cap() -> None:
    lim = Limits.from_section(demo_section())
    assert lim.jog_fraction(0) is None and lim.jog_fraction(-0.5) is None and lim.jog_fraction(math.inf) is None
    assert lim.jog_fraction(0.3) == 0.3 and lim.jog_fraction(4) == 1.0
    assert lim.joint_jog_speed(0.5) == 0.5
    # 0.8 m from the joint axis at 1 rad/s would be 0.8 m/s at the TCP: capped to 0.25 m/s
    assert lim.joint_jog_speed(1.0, lever=0.8) == pytest.approx(CAP / 0.8)
    assert lim.joint_jog_speed(1.0, lever=0.1) == 1.0  # a short lever: max_speed is the limit


# ---------------------------------------------------------------------------------------------- frames
def test_rotation_vector_round_trip_including_half_turns() -> None:
    rng = np.random.default_rng(1)
    for _ in range(200):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        r = axis * rng.uniform(0, math.pi)
        m = frames.rotvec_to_matrix(r)
        np.testing.assert_allclose(m @ m.T, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(frames.rotvec_to_matrix(frames.matrix_to_rotvec(m)), m, atol=1e-9)
    half = frames.rotvec_to_matrix([0, math.pi, 0])
    assert abs(np.linalg.norm(frames.matrix_to_rotvec(half)) - math.pi) < 1e-9
    np.testing.assert_allclose(frames.rotvec_to_matrix([0, 0, math.pi / 2]) @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    x, y, z, w = frames.rotvec_to_quaternion([0, 0, math.pi / 2])
    assert (x, y) == (0, 0) and z == pytest.approx(math.sqrt(0.5)) and w == pytest.approx(math.sqrt(0.5))


def test_relative_offset_in_base_and_tool_frame() -> None:
    # Tool pointing down (half turn about base Y): tool z = -base z, tool x = -base x.
    pose = [0.4, -0.1, 0.3, 0.0, math.pi, 0.0]
    up = frames.relative_target(pose, [0, 0, 0.05, 0, 0, 0], "base")
    np.testing.assert_allclose(up[:3], [0.4, -0.1, 0.35], atol=1e-12)
    np.testing.assert_allclose(frames.rotvec_to_matrix(up[3:]), frames.rotvec_to_matrix(pose[3:]), atol=1e-12)
    down = frames.relative_target(pose, [0.01, 0, 0.05, 0, 0, 0], "tool")  # along the tool axes
    np.testing.assert_allclose(down[:3], [0.39, -0.1, 0.25], atol=1e-12)
    # Rotations: base frame turns about a base axis through the TCP; tool frame about the tool's own axis.
    turned = frames.relative_target(pose, [0, 0, 0, 0, 0, 0.3], "base")
    np.testing.assert_allclose(turned[:3], pose[:3], atol=1e-12)
    np.testing.assert_allclose(frames.rotvec_to_matrix(turned[3:]),
                               frames.rotvec_to_matrix([0, 0, 0.3]) @ frames.rotvec_to_matrix(pose[3:]), atol=1e-12)
    spun = frames.relative_target(pose, [0, 0, 0, 0, 0, 0.3], "tool")
    np.testing.assert_allclose(frames.rotvec_to_matrix(spun[3:]),
                               frames.rotvec_to_matrix(pose[3:]) @ frames.rotvec_to_matrix([0, 0, 0.3]), atol=1e-12)
    with pytest.raises(ValueError):
        frames.relative_target(pose, [0] * 6, "world")
    d, a = frames.pose_distance(pose, down)
    assert d == pytest.approx(math.hypot(0.01, 0.05)) and a == pytest.approx(0, abs=1e-9)


def test_tool_frame_jog_twist_is_rotated_into_the_base_frame() -> None:
    down = [0.4, -0.1, 0.3, 0.0, math.pi, 0.0]
    np.testing.assert_allclose(frames.tool_twist_to_base([0, 0, 0.25, 0, 0, 0], down), [0, 0, -0.25, 0, 0, 0],
                               atol=1e-12)
    np.testing.assert_allclose(frames.tool_twist_to_base([0.1, 0, 0, 0, 0, 0.5], down), [-0.1, 0, 0, 0, 0, -0.5],
                               atol=1e-12)
    turned = [0, 0, 0, 0, 0, math.pi / 2]  # tool x = base y
    np.testing.assert_allclose(frames.tool_twist_to_base([0.2, 0, 0, 0.3, 0, 0], turned), [0, 0.2, 0, 0, 0.3, 0],
                               atol=1e-12)


def test_fk_lever_is_the_distance_from_the_joint_axis() -> None:
    # A planar arm turning about z at the origin with its TCP 0.6 m out.
    fk = lambda q: [0.6 * math.cos(q[0]), 0.6 * math.sin(q[0]), 0.2, 0, 0, 0]  # noqa: E731
    assert fk_lever(fk, [0.3] * 6, 0) == pytest.approx(0.6, rel=1e-9)


# ---------------------------------------------------------------------------------------------- jog supervisor
class FakeClock:
    def __init__(self) -> None:
        self.t = 1000.0
        self._lock = threading.Lock()

    def __call__(self) -> float:
        return self.t

    def sleep(self, s: float) -> None:
        with self._lock:
            self.t += max(s, 1e-4)
        time.sleep(0)  # let other threads run


def jog(**kw) -> Jog:
    base = dict(group="arm", mode="joint", axis=0, direction=1, speed=0.5, frame="base")
    base.update(kw)
    return Jog(**base)  # type: ignore[arg-type]


def test_supervisor_heartbeat_timeout_with_a_fake_clock() -> None:
    clock = FakeClock()
    sup = JogSupervisor(0.2, clock)
    assert sup.command(jog()) is Decision.START
    for _ in range(10):  # 50 ms heartbeats keep it alive
        clock.t += 0.05
        assert sup.command(jog()) is Decision.HEARTBEAT
        assert not sup.expired()
    clock.t += 0.19
    assert not sup.expired()
    clock.t += 0.02  # 0.21 s since the last heartbeat
    assert sup.expired()
    assert sup.clear() == jog() and not sup.expired() and sup.active is None
    # stopped other than by its release: the same press stays stopped; a new press, or a release, ends that
    assert sup.command(jog()) is Decision.HELD and sup.active is None
    assert sup.command(jog(press=2)) is Decision.START
    sup.clear()
    assert sup.command(jog(direction=0)) is Decision.NOTHING
    assert sup.command(jog(press=2)) is Decision.START


def test_a_heartbeat_that_comes_after_its_press_was_released_does_not_start_the_arm() -> None:
    # CI: Stop robot from another session, the holder's release and a delayed heartbeat of that press: the heartbeat
    # after the release started the arm again for a moment (0.12 rad/s).
    sup = JogSupervisor(0.2, FakeClock())
    assert sup.command(jog(press=7)) is Decision.START
    assert sup.command(jog(press=7, direction=0)) is Decision.STOP
    assert sup.command(jog(press=7)) is Decision.HELD and sup.active is None
    assert sup.command(jog(press=7, axis=2)) is Decision.HELD            # whatever that press's message says
    assert sup.command(jog(press=8)) is Decision.START                   # the next press moves
    assert sup.command(jog(press=7, group="other")) is Decision.START    # another group's press numbers are its own
    # a publisher without press numbers (press 0) jogs as before: release, then the same message starts again
    sup2 = JogSupervisor(0.2, FakeClock())
    assert sup2.command(jog()) is Decision.START
    assert sup2.command(jog(direction=0)) is Decision.STOP
    assert sup2.command(jog()) is Decision.START


def test_supervisor_stop_replace_never_queue() -> None:
    clock = FakeClock()
    sup = JogSupervisor(0.2, clock)
    assert sup.command(jog(direction=0)) is Decision.NOTHING
    assert sup.command(jog()) is Decision.START
    assert sup.command(jog(direction=-1)) is Decision.START   # replaces at once
    assert sup.active == jog(direction=-1)
    assert sup.command(jog(direction=-1, speed=0.8)) is Decision.START  # a new slider value is a new command
    assert sup.command(jog(mode="cartesian", axis=2)) is Decision.START
    assert sup.command(jog(direction=0)) is Decision.STOP
    assert sup.active is None
    assert sup.command(jog(direction=0)) is Decision.NOTHING
    assert jog(axis=1, direction=-1).label() == "joint 2 -"
    assert jog(mode="cartesian", axis=4, frame="tool").label() == "RY + (tool)"
    # said with codes, so "jogging joint 2 -" reads "articulación 2 -" in Spanish (issue 29)
    labels = [jog(axis=1, direction=-1).label(), jog(mode="cartesian", axis=0).label(),
              jog(mode="cartesian", axis=4, frame="tool").label()]
    assert [x.code for x in labels] == ["manual.jog_joint", "manual.jog_axis", "manual.jog_axis_tool"]
    assert dict(labels[0].params) == {"joint": "2", "sign": "-"}
    for x in labels:
        check_said(say("manual.jogging", "jogging {jog}", jog=x))


# ---------------------------------------------------------------------------------------------- cell file
def test_demo_cell_section_parses_into_groups_and_tool_steps() -> None:
    cfg = parse_manual(demo_section())
    arm = cfg.groups["arm"]
    assert arm.indices == (0, 1, 2, 3, 4, 5) and arm.configurations["home"] == tuple(HOME)
    close = cfg.tools["gripper"].actions["close"].steps
    assert close[0] == DigitalOut(0, True) and isinstance(close[1], WaitInput) and isinstance(close[-1], Wait)
    assert cfg.tools["gripper"].actions["open"].steps[0] == DigitalOut(0, False)
    assert cfg.limits["max_tcp_speed"] == 0.25


@pytest.mark.parametrize("change, where", [
    (lambda s: s["groups"][0]["joints"].__setitem__(2, "knee"), "manual.groups[0].joints[2]: 'knee'"),
    (lambda s: s["groups"][0]["configurations"].__setitem__("bad", [0, 1]), "configurations.bad: 2 values for 6"),
    (lambda s: s["tools"][0]["actions"][0]["steps"].append({"fly": 1}), "steps[3]: unknown step"),
    (lambda s: s["tools"][0]["actions"][0]["steps"].append({"move_named": "nowhere", "group": "arm"}),
     "no configuration 'nowhere'"),
    (lambda s: s["tools"][0]["actions"][0]["steps"].append({"digital_out": 12, "value": True}), "digital_out"),
    (lambda s: s.__setitem__("max_speed", "fast"), "manual.max_speed: expected a number"),
])
def test_unusable_sections_name_the_field(change, where: str) -> None:
    section = demo_section()
    change(section)
    with pytest.raises(ConfigError, match=None) as e:
        parse_manual(section)
    assert where in str(e.value)


def test_tool_steps_of_every_kind() -> None:
    section = demo_section()
    section["tools"].append({"name": "changer", "actions": [{"name": "swap", "steps": [
        {"move_named": "home", "group": "arm"}, {"wait_input": 2, "value": True}, {"wait_s": 0}]}]})
    steps = parse_manual(section).tools["changer"].actions["swap"].steps
    assert steps == (MoveNamedStep("home", "arm"), WaitInput(2, True, 5.0), Wait(0.0))


# ---------------------------------------------------------------------------------------------- the gate
def test_gate_bounds_a_call_that_never_returns() -> None:
    gate = Gate(timeout=0.2)
    blocker = threading.Event()
    assert gate.call(lambda: 41 + 1) == 42
    t0 = time.monotonic()
    with pytest.raises(CallTimeout):
        gate.call(blocker.wait)  # like a ur_rtde call to a controller that vanished
    assert time.monotonic() - t0 < 0.5
    assert gate.call(lambda: "next call works") == "next call works"  # a fresh worker, the lock is free
    with pytest.raises(ZeroDivisionError):
        gate.call(lambda: 1 / 0)
    blocker.set()
    gate.close()


# ---------------------------------------------------------------------------------------------- the driver
class FakeRobot:
    """A controller with the ur_rtde interfaces' names: moves complete on the next progress poll."""

    def __init__(self) -> None:
        self.q = list(HOME)
        self.qd = [0.0] * 6
        self.pose = [0.1, -0.49, 0.43, 0.0, math.pi, 0.0]
        self.robot_mode, self.safety_mode, self.runtime = 7, 1, 2
        self.reachable = True
        self.connected = True
        self.ik_ok = True
        self.joint_limit = 2 * math.pi  # what isJointsWithinSafetyLimits allows, rad
        self.controls = 0          # control clients made (each uploads the control script)
        self.di = 1
        self.do = 0
        self.ts = 0.0
        self.calls: list[tuple] = []
        self.pending: Optional[tuple] = None
        self.hold = False          # keep moves running until released
        self.gripper_sensor = True  # DI1 follows DO0, like the sim's gripper
        self.lock = threading.Lock()
        self.closed: list[str] = []  # clients disconnected, by kind
        self.stall: dict[str, threading.Event] = {}  # a control call that does not return until its event is set
        self.inside = threading.Event()             # set when a stalled call is entered

    # what a test looks at
    def moves(self, name: str) -> list[tuple]:
        return [c for c in self.calls if c[0] == name]


class FakeReceive:
    def __init__(self, robot: FakeRobot) -> None:
        self.r = robot

    def isConnected(self) -> bool: return self.r.connected
    def disconnect(self) -> None: self.r.closed.append("receive")

    def getTimestamp(self) -> float:
        self.r.ts += 0.002
        return self.r.ts

    def getActualQ(self): return list(self.r.q)
    def getActualQd(self): return list(self.r.qd)
    def getActualTCPPose(self): return list(self.r.pose)
    def getActualTCPSpeed(self): return [0.0] * 6
    def getRobotMode(self): return self.r.robot_mode
    def getSafetyMode(self): return self.r.safety_mode
    def getSpeedScaling(self): return 1.0
    def getRuntimeState(self): return self.r.runtime
    def getActualDigitalInputBits(self): return self.r.di
    def getActualDigitalOutputBits(self): return self.r.do


class FakeControl:
    def __init__(self, robot: FakeRobot) -> None:
        self.r = robot

    def _rec(self, *call) -> None:
        self.r.calls.append(call)

    def isConnected(self): return self.r.connected
    def isProgramRunning(self): return self.r.runtime == 2
    def reuploadScript(self): self._rec("reuploadScript"); self.r.runtime = 2; return True
    def stopScript(self): self._rec("stopScript")
    def disconnect(self): self.r.closed.append("control")

    def _stall(self, name: str) -> None:
        if name in self.r.stall:
            self.r.inside.set()
            self.r.stall[name].wait(10)

    def moveJ(self, q, speed, acceleration, asynchronous):
        self._rec("moveJ", list(q), speed, acceleration, asynchronous)
        self.r.pending = ("q", list(q))
        return True

    def moveL(self, pose, speed, acceleration, asynchronous):
        self._rec("moveL", list(pose), speed, acceleration, asynchronous)
        self.r.pending = ("pose", list(pose))
        return True

    def getAsyncOperationProgress(self) -> int:
        self._stall("getAsyncOperationProgress")
        if self.r.pending is None:
            return -1
        if self.r.hold:
            return 0
        kind, target = self.r.pending
        if kind == "q":
            self.r.q = target
        else:  # a moveL ends where the controller's IK from the start joints says
            self.r.q = fake_ik(target, self.r.q)
            self.r.pose = target
        self.r.pending = None
        return 0

    def speedJ(self, qd, acceleration, time):
        self._stall("speedJ")
        self._rec("speedJ", list(qd), acceleration)
        self.r.qd = list(qd)
        return True

    def speedL(self, xd, acceleration, time):
        self._rec("speedL", list(xd), acceleration)
        self.r.qd = [0.1] * 6
        return True

    def speedStop(self, a):
        self._rec("speedStop", a)
        self.r.qd = [0.0] * 6
        return True

    def stopJ(self, a, asynchronous):
        self._rec("stopJ", a, asynchronous)
        self.r.pending = None
        self.r.qd = [0.0] * 6

    def stopL(self, a, asynchronous):
        self._rec("stopL", a, asynchronous)
        self.r.pending = None

    def getInverseKinematicsHasSolution(self, x, qnear, max_position_error, max_orientation_error):
        self._rec("ik", list(x))
        return self.r.ik_ok

    def getInverseKinematics(self, x, qnear, max_position_error, max_orientation_error):
        self._rec("getInverseKinematics", list(x), list(qnear))
        assert self.r.ik_ok, "get_inverse_kin without a solution ends the control script"
        return fake_ik(x, qnear)

    def isJointsWithinSafetyLimits(self, q):
        self._rec("isJointsWithinSafetyLimits", list(q))
        return all(abs(v) <= self.r.joint_limit for v in q)

    def getForwardKinematics(self, q, tcp_offset):
        # the base joint turns the TCP on a 0.5 m circle
        return [0.5 * math.cos(q[0]), 0.5 * math.sin(q[0]), 0.4, 0.0, math.pi, 0.0]

    def getTCPOffset(self): return [0, 0, 0.125, 0, 0, 0]


def fake_ik(pose, qnear) -> list[float]:
    """The fake controller's IK: a solution near qnear that depends on the pose (the base joint points at it)."""
    q = list(qnear)
    q[0] = math.atan2(pose[1], pose[0])
    q[1] = qnear[1] - (pose[2] - 0.43)
    return q


class FakeIO:
    def __init__(self, robot: FakeRobot) -> None:
        self.r = robot

    def setStandardDigitalOut(self, output_id: int, signal_level: bool) -> bool:
        self.r.calls.append(("setStandardDigitalOut", output_id, signal_level))
        bit = 1 << output_id
        self.r.do = (self.r.do | bit) if signal_level else (self.r.do & ~bit)
        if output_id == 0 and self.r.gripper_sensor:  # a gripper reporting "closed" on DI1, like the sim
            self.r.di = (self.r.di | 2) if signal_level else (self.r.di & ~2)
        return True

    def disconnect(self) -> None: self.r.closed.append("io")


class FakeConnector:
    def __init__(self, robot: FakeRobot) -> None:
        self.r = robot

    def _check(self) -> None:
        if not self.r.reachable:
            raise RuntimeError("connection refused")

    def receive(self, host):
        self._check()
        self.r.connected = True
        return FakeReceive(self.r)

    def io(self, host):
        self._check()
        return FakeIO(self.r)

    def control(self, host):
        self._check()
        self.r.controls += 1
        return FakeControl(self.r)

    def dashboard(self, host):
        self._check()
        return FakeDashboard(self.r)


class FakeDashboard:
    def __init__(self, robot: FakeRobot) -> None:
        self.r = robot

    def connect(self, timeout_ms: int = 2000) -> None: pass
    def disconnect(self) -> None: pass

    def stop(self) -> None:
        self.r.calls.append(("dashboard stop",))
        self.r.qd = [0.0] * 6
        self.r.runtime = 1


def make_driver(robot: FakeRobot, section: Optional[dict] = None, clock: Optional[FakeClock] = None,
                call_timeout: float = 1.0) -> ManualDriver:
    section = section or demo_section()
    clock = clock or FakeClock()
    d = ManualDriver(parse_manual(section), "10.0.0.5", FakeConnector(robot), Limits.from_section(parse_manual(
        section).limits), clock=clock, sleep=clock.sleep, call_timeout=call_timeout)
    return d


@pytest.fixture
def robot() -> FakeRobot:
    return FakeRobot()


@pytest.fixture
def driver(robot: FakeRobot) -> ManualDriver:
    d = make_driver(robot)
    assert d.connect()
    return d


def test_unreachable_controller_is_refused_with_its_address(robot: FakeRobot) -> None:
    robot.reachable = False
    d = make_driver(robot)
    assert not d.connect()
    assert d.state().message == "robot controller at 10.0.0.5 is unreachable"
    assert d.state().connected is False
    for result in (d.move_named("arm", "home"), d.move_relative("arm", [0, 0, 0.05, 0, 0, 0], "base"),
                   d.move_pose("arm", robot.pose), d.tool_action("gripper", "close")):
        assert result == (False, "robot controller at 10.0.0.5 is unreachable")
    assert robot.calls == []


@pytest.mark.parametrize("robot_mode, safety_mode, message", [
    (3, 1, "robot is not powered on (mode POWER_OFF)"),
    (5, 1, "robot brakes are not released (mode IDLE)"),
    (7, 3, "protective stop is active: clear it first"),
    (7, 5, "safeguard stop is active: close the guard first"),
    (7, 7, "emergency stop is active (ROBOT_EMERGENCY_STOP): release it first"),
])
def test_refusals_for_robot_and_safety_modes_leave_the_arm_alone(robot: FakeRobot, driver: ManualDriver,
                                                                  robot_mode: int, safety_mode: int, message: str) -> None:
    robot.robot_mode, robot.safety_mode = robot_mode, safety_mode
    driver.poll()
    assert driver.move_named("arm", "home") == (False, message)
    assert driver.move_pose("arm", robot.pose) == (False, message)
    assert driver.tool_action("gripper", "open") == (False, message)
    driver.jog("arm", "joint", 0, 1, 1.0, "base")
    assert driver.state().message == f"jog refused: {message}" and driver.state().motion == "idle"
    assert robot.calls == []


def test_unknown_names_and_bad_arguments_are_refused(robot: FakeRobot, driver: ManualDriver) -> None:
    assert driver.move_named("legs", "home") == (False, "unknown motion group 'legs' (the cell has: arm)")
    assert driver.move_named("arm", "dance") == (
        False, "unknown configuration 'dance' for group arm (it has: home, pick_approach)")
    assert driver.tool_action("laser", "fire") == (False, "unknown tool 'laser' (the cell has: gripper)")
    assert driver.tool_action("gripper", "crush") == (False, "unknown action 'crush' for tool gripper (it has: open, close, check_part)")
    ok, why = driver.move_relative("arm", [0, 0, 0.05], "base")
    assert not ok and why.startswith("offset must be 6 numbers") and "got 3" in why
    assert driver.move_relative("arm", [0] * 6, "world") == (False, "unknown frame 'world' (base or tool)")
    ok, why = driver.move_pose("arm", [0.1, 0.2, math.nan, 0, 0, 0])
    assert not ok and why.startswith("pose must be 6 numbers")
    assert driver.get_pose("legs")[0] is False
    assert robot.calls == []


def test_ik_failure_refuses_and_the_arm_does_not_move(robot: FakeRobot, driver: ManualDriver) -> None:
    robot.ik_ok = False
    assert driver.move_pose("arm", [2.0, 0, 0, 0, 0, 0]) == (False, "pose unreachable: no inverse kinematics solution")
    assert robot.moves("ik") and not robot.moves("moveL") and not robot.moves("moveJ")
    assert driver.state().motion == "idle"
    assert driver.state().message == "pose unreachable: no inverse kinematics solution"


def test_moves_are_asynchronous_and_clamped_to_the_cell_maxima(robot: FakeRobot) -> None:
    section = demo_section()
    section["max_tcp_speed"] = 2.0  # a cell file the schema would refuse: the driver caps it anyway
    d = make_driver(robot, section)
    assert d.connect()
    assert d.move_named("arm", "pick_approach", speed=50.0, acceleration=50.0) == (True, "arrived at pick_approach")
    (_, q, v, a, is_async), = robot.moves("moveJ")
    assert q == demo_section()["groups"][0]["configurations"]["pick_approach"]
    assert (v, a, is_async) == (1.0, 1.5, True)
    assert d.move_named("arm", "home") == (True, "arrived at home")
    assert robot.moves("moveJ")[-1][2:] == (0.25, 0.5, True)  # 0 = the cell's defaults
    start = list(robot.pose)
    assert d.move_relative("arm", [0, 0, 0.05, 0, 0, 0], "base", speed=3.0, acceleration=9.0) == \
        (True, "arrived at the relative target")
    (_, pose, v, a, is_async), = robot.moves("moveL")
    np.testing.assert_allclose(pose[:3], [start[0], start[1], start[2] + 0.05], atol=1e-12)
    assert (v, a, is_async) == (CAP, 1.0, True)
    assert d.move_pose("arm", start, speed=0.0) == (True, "arrived at the pose target")
    assert robot.moves("moveL")[-1][2] == 0.1
    assert d.state().motion == "idle" and d.state().progress == 1.0


def test_a_group_of_some_joints_keeps_the_others(robot: FakeRobot) -> None:
    section = demo_section()
    section["groups"].append({"name": "wrist", "joints": ["wrist_3_joint", "wrist_1_joint"],
                              "configurations": {"flat": [1.0, -1.0]}})
    d = make_driver(robot, section)
    assert d.connect()
    assert d.move_named("wrist", "flat")[0]
    q = robot.moves("moveJ")[-1][1]
    assert q == [HOME[0], HOME[1], HOME[2], -1.0, HOME[4], 1.0]
    ok, message, joints, tcp = d.get_pose("wrist")
    assert ok and joints == [1.0, -1.0] and len(tcp) == 6


def test_another_move_running_is_refused_and_stop_ends_it(robot: FakeRobot) -> None:
    d = ManualDriver(parse_manual(demo_section()), "10.0.0.5", FakeConnector(robot),
                     Limits.from_section(demo_section()))  # the real clock: two threads
    assert d.connect()
    robot.hold = True
    result: dict = {}
    mover = threading.Thread(target=lambda: result.setdefault("r", d.move_named("arm", "pick_approach")))
    mover.start()
    wait_for(lambda: robot.moves("moveJ"), 5, what="the move sent")
    assert d.state().motion == "moving" and d.state().motion_target == "pick_approach"
    assert d.move_named("arm", "home") == (False, "another move is running (pick_approach): stop it first")
    assert d.tool_action("gripper", "open") == (False, "another move is running (pick_approach): stop it first")
    d.jog("arm", "joint", 0, 1, 0.5, "base")
    assert not robot.moves("speedJ")
    assert d.state().message == "jog ignored: a move is running (pick_approach)"
    assert d.stop() == (True, "stopped")
    mover.join(5)
    assert result["r"] == (False, "stopped")
    assert robot.moves("stopJ") == [("stopJ", STOP_DECEL_JOINT, True)]
    assert len(robot.moves("moveJ")) == 1
    assert d.state().motion == "idle"
    robot.hold = False
    assert d.move_named("arm", "home") == (True, "arrived at home")


def test_jog_heartbeat_timeout_stops_the_arm(robot: FakeRobot) -> None:
    clock = FakeClock()
    d = make_driver(robot, clock=clock)
    assert d.connect()
    d.jog("arm", "joint", 1, -1, 0.5, "base")
    (_, qd, acc), = robot.moves("speedJ")
    assert qd == [0, -0.5, 0, 0, 0, 0] and acc == 1.5
    assert d.state().motion == "jogging" and d.state().motion_target == "joint 2 -"
    for _ in range(6):  # heartbeats every 50 ms: no new command, no stop
        clock.t += 0.05
        d.jog("arm", "joint", 1, -1, 0.5, "base")
        assert not d.check_heartbeat()
    assert len(robot.moves("speedJ")) == 1 and not robot.moves("speedStop")
    clock.t += 0.15
    assert not d.check_heartbeat()
    clock.t += 0.06  # 0.21 s without a heartbeat
    assert d.check_heartbeat()
    assert robot.moves("speedStop") == [("speedStop", WATCHDOG_DECEL_JOINT)]  # a lost link stops harder
    assert d.state().message == "jog stopped: no heartbeat for 0.2 s"
    d.poll()  # the arm stands still: idle
    assert d.state().motion == "idle"
    assert not d.check_heartbeat()


def test_a_late_heartbeat_neither_restarts_nor_keeps_a_jog_alive(robot: FakeRobot) -> None:
    """CI: a session lost control during a jog; the watchdog stopped the arm, then its heartbeats, let through by the
    BFF before the take-over and held up in a stalled rosbridge, arrived and moved the arm again (28 mrad)."""
    clock = FakeClock()
    d = make_driver(robot, clock=clock)
    assert d.connect()
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01)
    assert len(robot.moves("speedJ")) == 1
    clock.t += 0.1
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.25)  # late: no heartbeat
    assert d.state().message == "jog ignored: it arrived 0.25 s after it was sent (more than the jog timeout, 0.20 s)"
    clock.t += 0.15
    assert d.check_heartbeat(), "the late one did not keep the jog alive"
    assert len(robot.moves("speedStop")) == 1
    d.poll()
    for age in (0.6, 0.55, 0.5):  # the backlog arrives: nothing moves
        d.jog("arm", "joint", 0, 1, 0.5, "base", age)
    assert len(robot.moves("speedJ")) == 1 and d.state().motion == "idle"
    d.jog("arm", "joint", 0, 1, 0.5, "base", None, press=2)  # unknown age (published on ROS directly): as before
    assert len(robot.moves("speedJ")) == 2
    d.jog("arm", "joint", 0, 0, 0.5, "base", 5.0)  # a release stops however late it comes
    assert len(robot.moves("speedStop")) == 2


def test_a_jog_stopped_while_its_button_is_held_stays_stopped_until_a_new_press(robot: FakeRobot) -> None:
    """"Stop robot" from another session while the holder's thumb stayed down: the holder's next heartbeat started
    the arm again (e2e, before the fix). A stop holds the press, and so does the heartbeat timeout: heartbeats that
    come again after a stall never restart the arm by themselves (issue 51: as a teach pendant's enabling switch)."""
    clock = FakeClock()
    d = make_driver(robot, clock=clock)
    assert d.connect()
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=7)
    assert d.stop()[0]  # Stop robot, the thumb still down
    d.poll()
    for _ in range(4):  # the same press's heartbeats go on: nothing moves
        clock.t += 0.05
        d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=7)
    assert len(robot.moves("speedJ")) == 1 and d.state().motion == "idle"
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=8)  # a new press moves
    assert len(robot.moves("speedJ")) == 2 and d.state().motion == "jogging"
    clock.t += 0.25  # a stall: the watchdog stops the arm...
    assert d.check_heartbeat()
    d.poll()
    for _ in range(4):  # ...and the same press's heartbeats, back after the stall, move nothing
        clock.t += 0.05
        d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=8)
        assert not d.check_heartbeat()
    assert len(robot.moves("speedJ")) == 2 and d.state().motion == "idle"
    assert d.state().message == "jog stopped: no heartbeat for 0.2 s"  # the page still says why
    d.jog("arm", "joint", 0, 0, 0.5, "base", 0.01, press=8)  # let go...
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=9)  # ...and press again: it moves
    assert len(robot.moves("speedJ")) == 3 and d.state().motion == "jogging"
    assert d.stop()[0]
    d.poll()
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=9)
    assert len(robot.moves("speedJ")) == 3 and d.state().motion == "idle"
    d.jog("arm", "joint", 0, -1, 0.5, "base", 0.01, press=9)  # a different jog is a new command
    assert len(robot.moves("speedJ")) == 4
    # A publisher without press numbers (0): after a stop or a stall, only a release lets it move again.
    d.jog("arm", "joint", 0, 1, 0.5, "base")
    assert len(robot.moves("speedJ")) == 5
    assert d.stop()[0]
    d.poll()
    d.jog("arm", "joint", 0, 1, 0.5, "base")
    assert len(robot.moves("speedJ")) == 5
    d.jog("arm", "joint", 0, 0, 0.5, "base")
    d.jog("arm", "joint", 0, 1, 0.5, "base")
    assert len(robot.moves("speedJ")) == 6
    clock.t += 0.25
    assert d.check_heartbeat()
    d.poll()
    d.jog("arm", "joint", 0, 1, 0.5, "base")
    assert len(robot.moves("speedJ")) == 6 and d.state().motion == "idle"


def test_why_a_held_button_does_not_move_the_arm_is_logged_once_per_press(robot: FakeRobot, caplog: Any) -> None:
    """A held button that moves nothing must be explainable from the node's log (the e2e failure context shows it),
    without a line per heartbeat."""
    caplog.set_level(logging.INFO, logger="cell_nodes.manual")
    clock = FakeClock()
    d = make_driver(robot, clock=clock)
    assert d.connect()
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=7)
    assert d.stop()[0]
    for _ in range(5):
        clock.t += 0.05
        d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=7)
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.9, press=8)  # late
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.9, press=8)
    lines = [r.getMessage() for r in caplog.records if r.name == "cell_nodes.manual"]
    assert [x for x in lines if x.startswith("jogging")] == ["jogging joint 1 + at 50 % (press 7)"]
    assert lines.count("jog joint 1 + (press 7) held: this press was stopped") == 1
    assert lines.count("jog joint 1 + (press 8) ignored: it came late (0.90 s after the BFF let it through)") == 1
    assert sum("ignored: it came late" in x for x in lines) == 1
    assert any(x.startswith("stopped") for x in lines), lines


def test_a_refused_jog_and_lateness_after_a_run_of_the_jog_are_logged_again(robot: FakeRobot, caplog: Any) -> None:
    """CI: a held button jogged twice, then moved nothing for 4 s and the log said nothing more: late heartbeats
    after a run of the jog, and refusals, must each leave a line (once, not per heartbeat)."""
    caplog.set_level(logging.INFO, logger="cell_nodes.manual")
    d = make_driver(robot, clock=FakeClock())
    assert d.connect()
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.5, press=3)   # late before the jog ran
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=3)  # runs
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.4, press=3)   # late again after the run
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.45, press=3)
    d.jog("arm", "joint", 9, 1, 0.5, "base", 0.01, press=4)  # no joint 10
    d.jog("arm", "joint", 9, 1, 0.5, "base", 0.01, press=4)
    lines = [r.getMessage() for r in caplog.records if r.name == "cell_nodes.manual"]
    late = [x for x in lines if "came late" in x]
    assert late == ["jog joint 1 + (press 3) ignored: it came late (0.50 s after the BFF let it through)",
                    "jog joint 1 + (press 3) ignored: it came late (0.40 s after the BFF let it through)"], lines
    refused = [x for x in lines if "(press 4) refused" in x]
    assert refused == ["jog joint 10 + (press 4) refused: group arm has no joint 10"], lines


def test_a_refused_jog_start_is_tried_again_by_the_same_press(robot: FakeRobot) -> None:
    # e2e (loaded host): the first speedJ of a press failed, and holding the press left the arm still for 15 s.
    d = make_driver(robot)
    assert d.connect()
    FakeControl.speedJ, saved = (lambda self, qd, acceleration, time: False), FakeControl.speedJ
    try:
        d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=3)
        assert d.state().message == "jog refused: the controller refused the joint jog"
    finally:
        FakeControl.speedJ = saved
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=3)
    assert d.state().motion == "jogging" and len(robot.moves("speedJ")) == 1


def test_jog_release_replace_and_caps(robot: FakeRobot) -> None:
    section = demo_section()
    section["max_tcp_speed"] = 0.9
    d = make_driver(robot, section)
    assert d.connect()
    d.jog("arm", "joint", 0, 1, 1.0, "base")  # the base joint 0.5 m from the TCP: 0.25 / 0.5 = 0.5 rad/s
    assert robot.moves("speedJ")[-1][1][0] == pytest.approx(CAP / 0.5, rel=1e-3)
    d.jog("arm", "cartesian", 0, 1, 1.0, "base")  # replaces at once: the joint jog stops, the Cartesian one starts
    assert robot.moves("speedStop")[-1] == ("speedStop", STOP_DECEL_JOINT)
    assert robot.moves("speedL")[-1][1] == [CAP, 0, 0, 0, 0, 0]  # full slider, capped under 0.25 m/s
    d.jog("arm", "cartesian", 2, 1, 0.4, "tool")  # tool z points down in the base frame
    np.testing.assert_allclose(robot.moves("speedL")[-1][1], [0, 0, -0.4 * CAP, 0, 0, 0], atol=1e-12)
    d.jog("arm", "cartesian", 5, -1, 1.0, "base")
    assert robot.moves("speedL")[-1][1] == [0, 0, 0, 0, 0, -1.0] and robot.moves("speedL")[-1][2] == 1.5
    assert d.state().motion_target == "RZ -"
    d.jog("arm", "cartesian", 5, 0, 1.0, "base")  # release
    assert robot.moves("speedStop")[-1] == ("speedStop", STOP_DECEL_TCP)
    assert d.state().motion in ("stopping", "idle") and d.state().message == "jog stopped"
    d.poll()
    assert d.state().motion == "idle"
    n = len(robot.calls)
    d.jog("arm", "joint", 9, 1, 1.0, "base")
    assert d.state().message == "jog refused: group arm has no joint 10" and len(robot.calls) == n
    d.jog("arm", "joint", 0, 1, 0.0, "base")
    assert d.state().message == "jog refused: jog speed must be above 0" and len(robot.calls) == n


def test_a_move_request_stops_a_running_jog_and_is_refused(robot: FakeRobot, driver: ManualDriver) -> None:
    driver.jog("arm", "cartesian", 1, -1, 0.5, "base")
    assert driver.move_named("arm", "home") == (False, "another move is running (jog Y -): stop it first")
    assert robot.moves("speedStop") == [("speedStop", STOP_DECEL_TCP)]
    assert driver.state().motion in ("stopping", "idle") and not robot.moves("moveJ")


def test_stop_is_always_allowed_and_answers(robot: FakeRobot, driver: ManualDriver) -> None:
    assert driver.stop() == (True, "stopped")  # nothing runs: no controller call
    assert robot.calls == []
    driver.jog("arm", "joint", 0, 1, 0.5, "base")
    assert driver.stop() == (True, "stopped")
    assert robot.moves("speedStop") and driver.state().motion == "idle"


def test_stop_robot_also_stops_a_program_the_driver_did_not_start(robot: FakeRobot, driver: ManualDriver) -> None:
    robot.qd = [0.3, 0, 0, 0, 0, 0]  # another program moves the arm
    driver.poll()
    assert driver.stop() == (True, "stopped")
    assert robot.calls == [("dashboard stop",)]
    robot.runtime = 2
    driver.poll()
    assert driver.stop() == (True, "stopped")  # the arm stands still: no program is stopped
    assert robot.calls == [("dashboard stop",)]


def test_tool_action_runs_its_steps(robot: FakeRobot, driver: ManualDriver) -> None:
    assert driver.tool_action("gripper", "close") == (True, "gripper close done")
    assert robot.moves("setStandardDigitalOut") == [("setStandardDigitalOut", 0, True)]
    assert driver.tool_action("gripper", "open") == (True, "gripper open done")
    assert robot.moves("setStandardDigitalOut")[-1] == ("setStandardDigitalOut", 0, False)
    assert not robot.moves("moveJ")


def test_tool_action_fails_when_its_input_never_comes(robot: FakeRobot, driver: ManualDriver) -> None:
    robot.gripper_sensor = False  # a stuck gripper: DI1 never reports "closed"
    assert driver.tool_action("gripper", "close") == (
        False, "gripper close: digital input 1 did not turn on within 2 s")
    assert driver.state().motion == "idle"


def test_tool_change_sequence_with_a_move(robot: FakeRobot) -> None:
    section = demo_section()
    section["tools"].append({"name": "changer", "actions": [{"name": "park", "steps": [
        {"move_named": "home", "group": "arm"}, {"digital_out": 3, "value": True}, {"wait_s": 0.1}]}]})
    d = make_driver(robot, section)
    assert d.connect()
    assert d.tool_action("changer", "park") == (True, "changer park done")
    names = [c[0] for c in robot.calls]
    assert names.index("moveJ") < names.index("setStandardDigitalOut")


def test_a_dwell_is_timed_on_the_controllers_clock(robot: FakeRobot) -> None:
    # A simulated controller at half real time (an overloaded host): the dwell lasts its 1 s of controller time.
    section = demo_section()
    section["tools"].append({"name": "clamp", "actions": [{"name": "settle", "steps": [{"wait_s": 1.0}]}]})
    clock = FakeClock()
    d = make_driver(robot, section, clock=clock)
    assert d.connect()
    FakeReceive.getTimestamp, saved = (lambda self: clock.t * 0.5), FakeReceive.getTimestamp
    try:
        t0 = clock.t
        assert d.tool_action("clamp", "settle") == (True, "clamp settle done")
        assert 2.0 <= clock.t - t0 < 2.1
        FakeReceive.getTimestamp = lambda self: 7.0  # a controller clock that stands still: 3x + 1 s at most
        t0 = clock.t
        assert d.tool_action("clamp", "settle") == (True, "clamp settle done")
        assert 4.0 <= clock.t - t0 < 4.1
    finally:
        FakeReceive.getTimestamp = saved


def test_script_reuploaded_after_a_protective_stop(robot: FakeRobot, driver: ManualDriver) -> None:
    assert driver.move_named("arm", "home")[0]
    robot.runtime = 1  # the control script ended (protective stop, since cleared)
    driver.poll()
    assert driver.move_named("arm", "pick_approach") == (True, "arrived at pick_approach")
    assert robot.moves("reuploadScript")


def test_controller_loss_and_reconnection(robot: FakeRobot, driver: ManualDriver) -> None:
    driver.jog("arm", "joint", 0, 1, 0.5, "base")
    changes: list[str] = []
    driver.on_change = lambda: changes.append(driver.state().message)
    robot.connected = False  # the controller restarts (and the arm stands still)
    robot.reachable = False
    robot.qd = [0.0] * 6
    driver.poll()
    s = driver.state()
    assert (s.connected, s.motion, s.message) == (False, "idle", "robot controller at 10.0.0.5 is unreachable")
    assert "robot controller at 10.0.0.5 is unreachable" in changes
    assert driver.move_named("arm", "home") == (False, "robot controller at 10.0.0.5 is unreachable")
    assert driver.stop() == (False, "robot controller at 10.0.0.5 is unreachable")
    assert not driver.connect()
    robot.reachable = True
    assert driver.connect()
    assert driver.state().connected and driver.state().message == "reconnected to the robot controller at 10.0.0.5"
    assert driver.move_named("arm", "home") == (True, "arrived at home")


def test_stale_data_means_the_controller_is_gone(robot: FakeRobot) -> None:
    clock = FakeClock()
    d = make_driver(robot, clock=clock)
    assert d.connect()
    FakeReceive.getTimestamp, saved = (lambda self: 5.0), FakeReceive.getTimestamp
    try:
        d.poll()
        clock.t += 0.5
        d.poll()
        assert d.connected
        clock.t += 0.6
        d.poll()
        assert not d.connected
    finally:
        FakeReceive.getTimestamp = saved


def test_a_dropped_client_closes_only_once_no_call_is_inside_it() -> None:
    inside, release = threading.Event(), threading.Event()
    events: list[str] = []

    class Client:
        def slow(self) -> int:
            inside.set()
            release.wait(10)
            events.append("slow returned")
            return 1

        def fast(self) -> int: return 2
        def disconnect(self) -> None: events.append("disconnect")

    g = Guarded(Client())
    assert g.fast() == 2 and hasattr(g, "fast") and not hasattr(g, "getMoveError")
    caller = threading.Thread(target=g.slow)
    caller.start()
    assert inside.wait(10)
    with pytest.raises(ClientGone):  # a second thread never enters a client another one is inside
        g.fast()
    dropper = threading.Thread(target=g.drop)
    dropper.start()
    dropper.join(0.3)
    assert dropper.is_alive() and events == []  # the disconnect waits for the call inside
    release.set()
    dropper.join(10)
    caller.join(10)
    assert events == ["slow returned", "disconnect"]
    with pytest.raises(ClientGone):
        g.fast()
    g.drop()
    assert events.count("disconnect") == 1


def test_a_lost_controller_is_never_disconnected_under_a_call_still_inside_it(robot: FakeRobot) -> None:
    # CI: the node died with SIGSEGV when, after a call the gate gave up on, the lost connection's clients were
    # disconnected while that call was still inside ur_rtde (its own reconnect met the disconnect).
    d = make_driver(robot, call_timeout=0.3)
    assert d.connect()
    assert d.move_named("arm", "home")[0]  # the control client exists
    release = threading.Event()
    robot.stall["speedJ"] = release
    jog = threading.Thread(target=d.jog, args=("arm", "joint", 0, 1, 0.5, "base"))
    jog.start()
    assert robot.inside.wait(10)
    wait_for(lambda: not d.connected, 10)
    wait_for(lambda: sorted(robot.closed) == ["io", "receive"], 10)  # the clients nobody is inside close at once
    assert robot.closed.count("control") == 0
    assert d.connect()  # a new connection meanwhile: moves are refused until it has its own control client
    release.set()
    wait_for(lambda: "control" in robot.closed, 10)  # the old one closes once its call came back
    jog.join(10)
    robot.qd = [0.0] * 6  # (the fake arm keeps the speed the late speedJ set)
    assert d.move_named("arm", "home") == (True, "arrived at home")  # through a new control client
    assert robot.controls == 2


def test_a_control_client_whose_process_died_is_replaced_on_the_next_move(robot: FakeRobot, driver: ManualDriver) -> None:
    assert driver.move_named("arm", "home")[0]
    dead = driver._ctl
    FakeControl.isConnected, saved = _dead, FakeControl.isConnected  # (ur_process: its child ended, e.g. a crash)
    try:
        assert driver.move_named("arm", "pick_approach") == (True, "arrived at pick_approach")
    finally:
        FakeControl.isConnected = saved
    assert robot.controls == 2 and driver._ctl is not dead and driver.connected


def _dead(self: FakeControl) -> bool:
    if self.r.controls < 2:  # the first client's process is gone; the new one answers
        raise RuntimeError("the ur_rtde control process for 10.0.0.5 ended (exit code -11)")
    return True


def test_groups_service_content(driver: ManualDriver) -> None:
    groups, tools, limits = driver.groups()
    assert [g.name for g in groups] == ["arm"] and tools == [("gripper", ["open", "close", "check_part"])]
    assert limits.as_dict() == {"default_speed": 0.25, "default_acceleration": 0.5, "max_speed": 1.0,
                                "max_acceleration": 1.5, "max_tcp_speed": 0.25, "max_tcp_acceleration": 1.0,
                                "jog_timeout": 0.2}


# ---------------------------------------------------------------------------------------------- the move preview
PICK = demo_section()["groups"][0]["configurations"]["pick_approach"]


@pytest.fixture
def idle_robot(robot: FakeRobot) -> FakeRobot:
    """No program runs on the controller (as a fresh UR): the driver's control script starts on first use."""
    robot.runtime = 1
    return robot


def test_preview_of_each_kind_is_the_target_the_move_then_commands(idle_robot: FakeRobot) -> None:
    robot = idle_robot
    d = make_driver(robot)
    assert d.connect()
    # named: the configuration, the TCP there from the controller's FK; the move sends exactly those joints
    ok, message, names, q, tcp = d.preview_move("arm", "named", "pick_approach")
    assert (ok, message, names) == (True, "pick_approach is reachable", list(UR_JOINTS))
    assert q == PICK and tcp == pytest.approx([0.5 * math.cos(PICK[0]), 0.5 * math.sin(PICK[0]), 0.4, 0, math.pi, 0])
    assert robot.moves("isJointsWithinSafetyLimits")[-1] == ("isJointsWithinSafetyLimits", PICK)
    assert not robot.moves("moveJ")
    assert d.move_named("arm", "pick_approach") == (True, "arrived at pick_approach")
    assert robot.moves("moveJ")[-1][1] == q
    # relative: from the current TCP pose; its joints are the controller's IK seeded with the current joints, and the
    # arm ends there (the fake controller's moveL ends at its IK from the start joints, as a real one does)
    start_q, start_pose = list(robot.q), list(robot.pose)
    ok, message, names, q, tcp = d.preview_move("arm", "relative", offset=[0, 0, 0.05, 0, 0, 0.2], frame="tool")
    assert (ok, message) == (True, "the relative target is reachable")
    assert tcp == pytest.approx(frames.relative_target(start_pose, [0, 0, 0.05, 0, 0, 0.2], "tool"))
    assert robot.moves("getInverseKinematics")[-1] == ("getInverseKinematics", tcp, start_q)
    assert q == fake_ik(tcp, start_q) and q != start_q
    assert d.move_relative("arm", [0, 0, 0.05, 0, 0, 0.2], "tool") == (True, "arrived at the relative target")
    assert robot.moves("moveL")[-1][1] == tcp          # the move commands the previewed pose
    assert robot.q == q and robot.pose == tcp           # and ends at the previewed joints
    # pose: as given, base frame
    pose = [0.2, -0.4, 0.3, 0.0, math.pi, 0.0]
    ok, message, names, q, tcp = d.preview_move("arm", "pose", pose=pose)
    assert (ok, message, tcp, q) == (True, "the pose target is reachable", pose, fake_ik(pose, robot.q))
    assert d.move_pose("arm", pose) == (True, "arrived at the pose target")
    assert robot.q == q


def test_the_preview_moves_nothing_claims_nothing_and_answers_while_a_move_runs(idle_robot: FakeRobot) -> None:
    robot = idle_robot
    d = ManualDriver(parse_manual(demo_section()), "10.0.0.5", FakeConnector(robot),
                     Limits.from_section(demo_section()))  # the real clock: two threads
    assert d.connect()
    assert d.preview_move("arm", "relative", offset=[0, 0, 0.05, 0, 0, 0], frame="base")[0]
    assert d.state().motion == "idle" and d.state().message == "connected to the robot controller at 10.0.0.5"
    motion = ("moveJ", "moveL", "speedJ", "speedL", "stopJ", "stopL", "speedStop")
    assert not [c for c in robot.calls if c[0] in motion]
    robot.hold = True
    result: dict = {}
    mover = threading.Thread(target=lambda: result.setdefault("r", d.move_named("arm", "pick_approach")))
    mover.start()
    wait_for(lambda: robot.moves("moveJ"), 5, what="the move sent")
    for request in (("named", "home"), ("relative", "", [0, 0, 0.02, 0, 0, 0], "base"), ("pose", "", (), "", robot.pose)):
        ok, message, _, q, tcp = d.preview_move("arm", *request)
        assert ok, message
        assert len(q) == 6 and len(tcp) == 6
    s = d.state()
    assert (s.motion, s.motion_target) == ("moving", "pick_approach")  # the running move keeps the arm
    assert len(robot.moves("moveJ")) == 1 and not robot.moves("moveL") and not robot.moves("stopJ")
    robot.hold = False
    mover.join(5)
    assert result["r"] == (True, "arrived at pick_approach")


def test_an_unreachable_target_is_refused_with_the_moves_own_words(idle_robot: FakeRobot) -> None:
    robot = idle_robot
    d = make_driver(robot)
    assert d.connect()
    robot.ik_ok = False
    far = [2.0, 0, 0, 0, 0, 0]
    preview = d.preview_move("arm", "pose", pose=far)
    assert preview == (False, "pose unreachable: no inverse kinematics solution", [], [], [])
    assert d.move_pose("arm", far) == (False, preview[1])
    assert d.preview_move("arm", "relative", offset=[0, 0, 0.5, 0, 0, 0], frame="base")[:2] == (False, preview[1])
    assert not robot.moves("getInverseKinematics")  # never asked without a solution (it would end the script)
    robot.ik_ok = True
    robot.joint_limit = 1.0  # the controller's safety limits refuse pick_approach's elbow (1.6 rad)
    refusal = "configuration pick_approach is outside the robot's safety limits (joint limits, safety planes or reach)"
    assert d.preview_move("arm", "named", "pick_approach") == (False, refusal, [], [], [])
    assert d.move_named("arm", "pick_approach") == (False, refusal)
    assert not robot.moves("moveJ") and not robot.moves("moveL") and d.state().motion == "idle"


@pytest.mark.parametrize("preview, move, message", [
    (("legs", "named", "home"), ("move_named", "legs", "home"), "unknown motion group 'legs' (the cell has: arm)"),
    (("arm", "named", "dance"), ("move_named", "arm", "dance"),
     "unknown configuration 'dance' for group arm (it has: home, pick_approach)"),
    (("arm", "relative", "", [0, 0, 0.05], "base"), ("move_relative", "arm", [0, 0, 0.05], "base"),
     "offset must be 6 numbers (x, y, z in m, rx, ry, rz in rad), got 3"),
    (("arm", "relative", "", [0, 0, math.nan, 0, 0, 0], "base"), ("move_relative", "arm", [0, 0, math.nan, 0, 0, 0],
                                                                  "base"),
     "offset must be 6 numbers (x, y, z in m, rx, ry, rz in rad), got nan for z"),
    (("arm", "relative", "", [0] * 6, "world"), ("move_relative", "arm", [0] * 6, "world"),
     "unknown frame 'world' (base or tool)"),
    (("arm", "pose", "", (), "", [0.1] * 7), ("move_pose", "arm", [0.1] * 7),
     "pose must be 6 numbers (x, y, z in m, rx, ry, rz in rad), got 7"),
    (("arm", "pose", "", (), "", [0.1, 0.2, 0.3, math.inf, 0, 0]), ("move_pose", "arm", [0.1, 0.2, 0.3, math.inf, 0, 0]),
     "pose must be 6 numbers (x, y, z in m, rx, ry, rz in rad), got inf for rx"),
    (("arm", "pose", "", (), "", []), ("move_pose", "arm", []),
     "pose must be 6 numbers (x, y, z in m, rx, ry, rz in rad), got 0"),
    (("arm", "jump", "home"), None, "unknown move kind 'jump' (named, relative or pose)"),
    (("arm", "", "home"), None, "unknown move kind '' (named, relative or pose)"),
])
def test_bad_preview_requests_are_refused_as_the_move_refuses_them(robot: FakeRobot, driver: ManualDriver,
                                                                   preview: tuple, move: Optional[tuple],
                                                                   message: str) -> None:
    assert driver.preview_move(*preview) == (False, message, [], [], [])
    if move is not None:
        assert getattr(driver, move[0])(*move[1:]) == (False, message)
    assert robot.calls == [] and robot.controls == 0  # nothing asked of the controller


def test_the_preview_refuses_as_the_move_when_the_arm_cannot_move(robot: FakeRobot, driver: ManualDriver) -> None:
    robot.robot_mode, robot.safety_mode = 7, 3
    driver.poll()
    assert driver.preview_move("arm", "named", "home") == (False, "protective stop is active: clear it first", [], [],
                                                          [])
    robot.reachable = robot.connected = False
    driver.poll()
    assert driver.preview_move("arm", "named", "home")[:2] == (False, "robot controller at 10.0.0.5 is unreachable")
    assert robot.calls == []


def test_the_preview_never_takes_the_controller_from_another_program(robot: FakeRobot, driver: ManualDriver) -> None:
    """A program runs on the controller (the fake's default) and the driver has no control client yet: making one
    would upload the control script and end that program, so the preview says so; a move does take over."""
    assert driver.snapshot().program_running
    assert driver.preview_move("arm", "named", "home") == (
        False, "another program runs on the robot controller: a preview does not take it over (a move would stop it)",
        [], [], [])
    assert robot.controls == 0
    assert driver.move_named("arm", "home") == (True, "arrived at home")
    assert robot.controls == 1
    assert driver.preview_move("arm", "named", "pick_approach")[:4] == (True, "pick_approach is reachable",
                                                                       list(UR_JOINTS), PICK)
    assert robot.controls == 1


def test_a_tool_step_moves_to_the_target_the_preview_shows(idle_robot: FakeRobot) -> None:
    section = demo_section()
    section["tools"].append({"name": "changer", "actions": [{"name": "park", "steps": [
        {"move_named": "pick_approach", "group": "arm"}]}]})
    d = make_driver(idle_robot, section)
    assert d.connect()
    q = d.preview_move("arm", "named", "pick_approach")[3]
    assert d.tool_action("changer", "park") == (True, "changer park done")
    assert idle_robot.moves("moveJ")[-1][1] == q
    idle_robot.joint_limit = 1.0
    assert d.tool_action("changer", "park") == (
        False, "changer park: configuration pick_approach is outside the robot's safety limits (joint limits, safety "
               "planes or reach)")


# ---------------------------------------------------------------------------------------------- hosts and arms
TWIN_JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
               "wrist_3_joint")


def twin_section(**hosts: str) -> dict:
    """Two arms (left: gripper; right: vacuum), joints named with a prefix, hosts from the file."""
    left_home = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]
    return {
        "groups": [
            {"name": "left", "host": hosts.get("left", "127.0.2.1"), "joints": [f"left_{j}" for j in TWIN_JOINTS],
             "configurations": {"home": left_home}},
            {"name": "right", "host": hosts.get("right", "127.0.2.2"), "joints": [f"right_{j}" for j in TWIN_JOINTS],
             "configurations": {"home": left_home, "out": [1.0, -1.2, 1.6, -1.97, -1.5708, 0.4]}},
        ],
        "tools": [
            {"name": "gripper", "actions": [{"name": "close", "steps": [{"digital_out": 0, "value": True}]}]},
            {"name": "vacuum", "group": "right", "actions": [
                {"name": "on", "steps": [{"digital_out": 4, "value": True}]},
                {"name": "park", "steps": [{"move_named": "out", "group": "right"}]}]},
        ],
        "max_speed": 1.0,
    }


def test_joint_names_end_with_a_ur_joint_which_gives_the_index() -> None:
    section = demo_section()
    section["groups"].append({"name": "wrist", "joints": ["tool_side_wrist_3_joint", "my_wrist_1_joint"]})
    cfg = parse_manual(section)
    assert cfg.groups["wrist"].indices == (5, 3)
    assert ur_joint_index("left_elbow_joint") == 2 and ur_joint_index("elbow") is None
    twin = parse_manual(twin_section())
    assert twin.groups["right"].joints[0] == "right_shoulder_pan_joint" and twin.groups["right"].indices == (
        0, 1, 2, 3, 4, 5)
    assert twin.groups["left"].host == "127.0.2.1" and cfg.groups["arm"].host is None
    section["groups"][1]["joints"].append("x_wrist_3_joint")
    with pytest.raises(ConfigError, match=r"^manual\.groups\[1\]\.joints\[2\]: 'x_wrist_3_joint' is the same robot "
                                          r"joint \(wrist_3_joint\) as joints\[0\]$"):
        parse_manual(section)


def test_a_tool_belongs_to_its_group_default_the_first() -> None:
    cfg = parse_manual(twin_section())
    assert (cfg.tools["gripper"].group, cfg.tools["vacuum"].group) == ("left", "right")
    assert parse_manual(demo_section()).tools["gripper"].group == "arm"
    bad = twin_section()
    bad["tools"][0]["group"] = "middle"
    with pytest.raises(ConfigError, match=r"^manual\.tools\[0\]\.group: 'middle' is not a motion group "
                                          r"\(manual\.groups: left, right\)$"):
        parse_manual(bad)


@pytest.mark.parametrize("section_hosts, environ, expected", [
    ({}, {}, {"left": "127.0.2.1", "right": "127.0.2.2"}),                                  # the file's hosts
    ({}, {"UR_HOSTS": "left=127.0.3.21,right=127.0.3.22"}, {"left": "127.0.3.21", "right": "127.0.3.22"}),
    ({}, {"UR_HOSTS": " right = 127.0.3.22 ,, ", "UR_HOST": "10.0.0.1"}, {"left": "127.0.2.1", "right": "127.0.3.22"}),
    ({"left": None, "right": None}, {"UR_HOST": "ur5.local"}, {"left": "ur5.local", "right": "ur5.local"}),
    ({"left": None, "right": None}, {}, {"left": "127.0.0.1", "right": "127.0.0.1"}),      # no host at all
    ({"left": None}, {"UR_HOST": " ", "UR_HOSTS": ""}, {"left": "127.0.0.1", "right": "127.0.2.2"}),
])
def test_resolve_hosts(section_hosts: dict, environ: dict, expected: dict) -> None:
    section = twin_section()
    for g in section["groups"]:
        if g["name"] in section_hosts and section_hosts[g["name"]] is None:
            del g["host"]
    assert resolve_hosts(section, environ) == expected


@pytest.mark.parametrize("environ, message", [
    ({"UR_HOSTS": "left"}, "UR_HOSTS: expected <group>=<host>[,<group>=<host>...], got 'left'"),
    ({"UR_HOSTS": "left=127.0.3.1,=x"}, "UR_HOSTS: expected <group>=<host>[,<group>=<host>...], got '=x'"),
    ({"UR_HOSTS": "middle=127.0.3.1"}, "UR_HOSTS: 'middle' is not a motion group of this cell (manual.groups: "
                                       "left, right)"),
    ({"UR_HOSTS": "left=not a host"}, "UR_HOSTS: left=not a host: expected a host name or an IPv4 address"),
    ({"UR_HOSTS": "left=300.1.1.1"}, "UR_HOSTS: left=300.1.1.1: expected a host name or an IPv4 address"),
])
def test_resolve_hosts_refuses_a_bad_environment(environ: dict, message: str) -> None:
    with pytest.raises(ConfigError) as e:
        resolve_hosts(twin_section(), environ)
    assert str(e.value) == message


def test_arms_are_the_groups_by_host_with_their_tools_and_joint_names() -> None:
    cfg = parse_manual(twin_section())
    left, right = plan_arms(cfg, resolve_hosts(twin_section(), {}))
    assert (left.host, left.groups, left.tools) == ("127.0.2.1", ("left",), ("gripper",))
    assert (right.host, right.groups, right.tools) == ("127.0.2.2", ("right",), ("vacuum",))
    assert left.joint_names == tuple(f"left_{j}" for j in TWIN_JOINTS)
    assert list(right.config(cfg).groups) == ["right"] and list(right.config(cfg).tools) == ["vacuum"]
    # the demo: one arm, the UR names, as before
    (arm,) = plan_arms(parse_manual(demo_section()), {"arm": "127.0.0.1"})
    assert arm.joint_names == TWIN_JOINTS and arm.groups == ("arm",) and arm.tools == ("gripper",)
    # groups of some joints on one arm: the joints no group names keep the arm's prefix
    section = {"groups": [{"name": "base", "joints": ["a_shoulder_pan_joint"]},
                          {"name": "wrist", "joints": ["a_wrist_3_joint", "a_wrist_2_joint"]}]}
    (one,) = plan_arms(parse_manual(section), {"base": "h1", "wrist": "h1"})
    assert one.joint_names == tuple(f"a_{j}" for j in TWIN_JOINTS) and one.groups == ("base", "wrist")


def test_arms_refuse_what_would_mix_them_up() -> None:
    cfg = parse_manual(twin_section())
    with pytest.raises(ConfigError, match=r"^manual\.groups\[1\]\.joints\[0\]: 'right_shoulder_pan_joint' is robot "
                                          r"joint shoulder_pan_joint of the arm at 127\.0\.0\.1, which group left calls "
                                          r"'left_shoulder_pan_joint'"):
        plan_arms(cfg, {"left": "127.0.0.1", "right": "127.0.0.1"})
    same = twin_section()
    same["groups"][1]["joints"] = list(same["groups"][0]["joints"])
    with pytest.raises(ConfigError, match=r"^manual\.groups\[1\]: joint name 'left_shoulder_pan_joint' is also a "
                                          r"joint of the arm at 127\.0\.2\.1 \(group left\)"):
        plan_arms(parse_manual(same), resolve_hosts(same, {}))
    cross = twin_section()
    cross["tools"][0]["actions"].append({"name": "hand", "steps": [{"move_named": "out", "group": "right"}]})
    with pytest.raises(ConfigError, match=r"^manual\.tools\[0\]\.actions\[1\]\.steps\[0\]: group 'right' is moved by "
                                          r"the controller at 127\.0\.2\.2, not by the tool's \(left\) at 127\.0\.2\.1$"):
        plan_arms(parse_manual(cross), resolve_hosts(cross, {}))


# ---------------------------------------------------------------------------------------------- the cell driver
class FakeArm:
    """A driver that records what reaches it and answers as told."""

    def __init__(self, host: str, groups: tuple[str, ...]) -> None:
        self.host = host
        self.groups = groups
        self.calls: list[tuple] = []
        self.on_change = lambda: None
        self.on_sample = lambda snap: None
        self.stop_answer = (True, "stopped")
        self.stop_delay = 0.0
        self.stopped_at: Optional[float] = None
        self.connected = True
        self.snap = Snapshot(connected=True, tcp_pose=(0.1, 0.2, 0.3, 0.0, 3.14, 0.0))

    def _rec(self, *call) -> tuple[bool, str]:
        self.calls.append(call)
        return True, f"{call[0]} on {self.host}"

    def start(self) -> None: self.calls.append(("start",))
    def shutdown(self) -> None: self.calls.append(("shutdown",))

    def state(self) -> DriverState:
        return DriverState(self.connected, self.host, "RUNNING", "NORMAL", 1.0, False, "idle", "", "", 1.0,
                           f"state of {self.host}", [0.0] * 6, list(self.snap.tcp_pose), [0.0] * 6)

    def snapshot(self) -> Snapshot: return self.snap
    def get_pose(self, group): self.calls.append(("get_pose", group)); return True, "pose", [1.0], [2.0] * 6
    def move_named(self, group, name, speed=0.0, acceleration=0.0): return self._rec("move_named", group, name)
    def move_relative(self, group, offset, frame, speed=0.0, acceleration=0.0):
        return self._rec("move_relative", group, tuple(offset), frame)
    def move_pose(self, group, pose, speed=0.0, acceleration=0.0): return self._rec("move_pose", group, tuple(pose))
    def tool_action(self, tool, action): return self._rec("tool", tool, action)

    def preview_move(self, group, kind, name="", offset=(), frame="", pose=()):
        self.calls.append(("preview_move", group, kind, name, tuple(offset), frame, tuple(pose)))
        return True, f"preview on {self.host}", [f"{group}_joint"], [0.5], [0.1] * 6

    def stop(self, wait: bool = True) -> tuple[bool, str]:
        self.calls.append(("stop",))
        time.sleep(self.stop_delay)
        self.stopped_at = time.monotonic()
        return self.stop_answer

    def jog(self, group, mode, axis, direction, speed, frame="base", age_s=None, press=0):
        self.calls.append(("jog", group, direction))
    def refuse_jog(self, why): self.calls.append(("refuse_jog", why))


def fake_cell(environ: Optional[dict] = None) -> tuple[CellDriver, FakeArm, FakeArm]:
    cfg = parse_manual(twin_section())
    made: list[FakeArm] = []

    def make(arm, arm_config):
        assert list(arm_config.groups) == list(arm.groups)
        made.append(FakeArm(arm.host, arm.groups))
        return made[-1]

    cell = CellDriver.build(cfg, resolve_hosts(twin_section(), environ or {}), Limits.from_section(cfg.limits), make)
    return cell, made[0], made[1]


def test_requests_go_to_the_groups_arm_and_tools_to_their_groups_arm() -> None:
    cell, left, right = fake_cell()
    assert cell.move_named("left", "home") == (True, "move_named on 127.0.2.1")
    assert cell.move_pose("right", [0.1] * 6) == (True, "move_pose on 127.0.2.2")
    assert cell.move_relative("right", [0, 0, 0.1, 0, 0, 0], "tool")[0]
    assert cell.get_pose("right") == (True, "pose", [1.0], [2.0] * 6)
    assert cell.tool_action("vacuum", "on") == (True, "tool on 127.0.2.2")
    assert cell.tool_action("gripper", "close") == (True, "tool on 127.0.2.1")
    assert left.calls == [("move_named", "left", "home"), ("tool", "gripper", "close")]
    assert right.calls == [("move_pose", "right", (0.1,) * 6), ("move_relative", "right", (0, 0, 0.1, 0, 0, 0), "tool"),
                           ("get_pose", "right"), ("tool", "vacuum", "on")]
    gs, tools, limits = cell.groups()
    assert [g.name for g in gs] == ["left", "right"]
    assert tools == [("gripper", ["close"], "left"), ("vacuum", ["on", "park"], "right")]
    assert limits.max_speed == 1.0


def test_unknown_names_are_refused_with_the_cells_names_and_reach_no_arm() -> None:
    cell, left, right = fake_cell()
    refusal = "unknown motion group 'middle' (the cell has: left, right)"
    assert cell.move_named("middle", "home") == (False, refusal)
    assert cell.move_pose("middle", [0] * 6) == (False, refusal)
    assert cell.move_relative("middle", [0] * 6, "base") == (False, refusal)
    assert cell.get_pose("middle") == (False, refusal, [], [])
    assert cell.tool_action("drill", "on") == (False, "unknown tool 'drill' (the cell has: gripper, vacuum)")
    assert left.calls == [] and right.calls == []
    cell.jog("middle", "joint", 0, 1, 0.5)           # refused on every arm: a running jog there stops
    assert left.calls == right.calls == [("refuse_jog", refusal)]
    cell.jog("middle", "joint", 0, 0, 0.5)           # a release reaches every arm
    assert left.calls[-1] == right.calls[-1] == ("jog", "middle", 0)
    with pytest.raises(KeyError):
        cell.state("middle")


def test_the_move_preview_goes_to_the_groups_arm() -> None:
    cell, left, right = fake_cell()
    assert cell.preview_move("right", "relative", "", [0, 0, 0.1, 0, 0, 0], "tool") == (
        True, "preview on 127.0.2.2", ["right_joint"], [0.5], [0.1] * 6)
    assert cell.preview_move("left", "named", "home")[1] == "preview on 127.0.2.1"
    assert cell.preview_move("right", "pose", pose=[0.2] * 6)[0]
    assert left.calls == [("preview_move", "left", "named", "home", (), "", ())]
    assert right.calls == [("preview_move", "right", "relative", "", (0, 0, 0.1, 0, 0, 0), "tool", ()),
                           ("preview_move", "right", "pose", "", (), "", (0.2,) * 6)]
    assert cell.preview_move("middle", "named", "home") == (
        False, "unknown motion group 'middle' (the cell has: left, right)", [], [], [])
    assert len(left.calls) == 1 and len(right.calls) == 2  # reached no arm


def test_jog_goes_to_its_groups_arm_only() -> None:
    cell, left, right = fake_cell()
    cell.jog("right", "joint", 2, -1, 0.5, "base")
    cell.jog("right", "joint", 2, 0, 0.5, "base")
    assert right.calls == [("jog", "right", -1), ("jog", "right", 0)] and left.calls == []


def test_stop_reaches_every_arm_at_once_and_answers_after_all() -> None:
    cell, left, right = fake_cell()
    left.stop_delay = right.stop_delay = 0.3
    t0 = time.monotonic()
    assert cell.stop() == (True, "stopped")
    took = time.monotonic() - t0
    assert ("stop",) in left.calls and ("stop",) in right.calls
    assert 0.3 <= took < 0.55                         # in parallel, and only once both answered
    assert abs(left.stopped_at - right.stopped_at) < 0.1
    right.stop_answer = (False, "robot controller at 127.0.2.2 is unreachable")
    right.stop_delay = left.stop_delay = 0.0
    assert cell.stop() == (False, "right: robot controller at 127.0.2.2 is unreachable (left stopped)")
    left.stop_answer = (False, "robot controller at 127.0.2.1 is unreachable")
    assert cell.stop() == (False, "left: robot controller at 127.0.2.1 is unreachable; right: robot controller at "
                                  "127.0.2.2 is unreachable")


def test_state_and_pose_per_group_and_change_reports_per_arm() -> None:
    cell, left, right = fake_cell()
    s = cell.state("right")
    assert (s.controller, s.motion_group, s.message) == ("127.0.2.2", "right", "state of 127.0.2.2")
    assert cell.state("left").motion_group == "left"
    assert cell.tcp_pose("left") == (0.1, 0.2, 0.3, 0.0, 3.14, 0.0)
    right.connected = False
    assert cell.tcp_pose("right") is None              # nothing to publish while unreachable
    changed: list = []
    samples: list = []
    cell.on_change = lambda arm: changed.append(arm.groups)
    cell.on_sample = lambda arm, snap: samples.append((arm.joint_names[0], snap))
    right.on_change()
    left.on_sample(left.snap)
    assert changed == [("right",)] and samples == [("left_shoulder_pan_joint", left.snap)]
    cell.start()
    cell.shutdown()
    assert left.calls == right.calls == [("start",), ("shutdown",)]


def test_one_host_for_both_groups_makes_one_arm() -> None:
    section = demo_section()
    section["groups"].append({"name": "wrist", "joints": ["wrist_3_joint", "wrist_1_joint"],
                              "configurations": {"flat": [1.0, -1.0]}})
    cfg = parse_manual(section)
    made: list[FakeArm] = []
    cell = CellDriver.build(cfg, resolve_hosts(section, {"UR_HOST": "10.0.0.5"}), Limits.from_section(cfg.limits),
                            lambda arm, c: made.append(FakeArm(arm.host, arm.groups)) or made[-1])
    (arm,) = made
    assert arm.groups == ("arm", "wrist") and [a.host for a in cell.arms] == ["10.0.0.5"]
    cell.move_named("wrist", "flat")
    assert cell.stop() == (True, "stopped")
    assert arm.calls == [("move_named", "wrist", "flat"), ("stop",)]


def test_two_real_drivers_move_their_own_robot(robot: FakeRobot) -> None:
    """The cell driver over two ManualDrivers on two fake controllers: each request moves only its arm; the tool's
    output is set on the tool's arm; stop reaches both; the joint names are each arm's own."""
    other = FakeRobot()
    robots = {"127.0.2.1": robot, "127.0.2.2": other}
    cfg = parse_manual(twin_section())
    limits = Limits.from_section(cfg.limits)
    cell = CellDriver.build(cfg, resolve_hosts(twin_section(), {}), limits,
                            lambda arm, c: ManualDriver(c, arm.host, FakeConnector(robots[arm.host]), limits,
                                                        joint_names=arm.joint_names))
    left, right = cell.drivers
    assert left.connect() and right.connect()
    assert right.joint_names[0] == "right_shoulder_pan_joint" and left.joint_names[5] == "left_wrist_3_joint"
    other.runtime = 1  # no program runs yet on the right arm's controller: its preview may start the control script
    right.poll()
    ok, _, names, q, _ = cell.preview_move("right", "named", "out")
    assert ok and names == [f"right_{j}" for j in TWIN_JOINTS] and q == twin_section()["groups"][1]["configurations"]["out"]
    assert cell.move_named("right", "out") == (True, "arrived at out")
    assert other.moves("moveJ") and not robot.moves("moveJ")
    assert other.moves("moveJ")[-1][1] == q
    assert cell.tool_action("vacuum", "on") == (True, "vacuum on done")
    assert other.moves("setStandardDigitalOut") == [("setStandardDigitalOut", 4, True)]
    assert not robot.moves("setStandardDigitalOut")
    assert cell.tool_action("gripper", "close") == (True, "gripper close done")
    assert robot.moves("setStandardDigitalOut") == [("setStandardDigitalOut", 0, True)]
    assert cell.move_named("left", "out") == (False, "unknown configuration 'out' for group left (it has: home)")
    cell.jog("left", "joint", 0, 1, 0.5, "base")
    assert robot.moves("speedJ") and not other.moves("speedJ")
    assert cell.state("left").motion == "jogging" and cell.state("right").motion == "idle"
    assert cell.stop() == (True, "stopped")
    assert robot.moves("speedStop") and cell.state("left").motion == "idle"


def test_the_dead_man_time_counts_from_when_the_controller_took_the_jog(robot: FakeRobot) -> None:
    """e2e beside another lane: starting a jog took longer than the jog timeout (a loaded host; the heartbeats that
    came meanwhile waited behind it), and the watchdog stopped the arm 1 ms after it started, for good (the press is
    held). The window starts once the controller took the jog."""
    clock = FakeClock()
    d = make_driver(robot, clock=clock)
    assert d.connect()
    start = d._start_jog

    def slow_start(cmd: Any, g: Any) -> None:
        clock.t += 0.3
        start(cmd, g)
    d._start_jog = slow_start  # type: ignore[method-assign]
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=3)
    assert d.state().motion == "jogging"
    assert not d.check_heartbeat(), "the watchdog counted the start's own time as missed heartbeats"
    clock.t += 0.05
    d.jog("arm", "joint", 0, 1, 0.5, "base", 0.01, press=3)
    clock.t += 0.19
    assert not d.check_heartbeat()
    clock.t += 0.02  # the operator's heartbeats did stop: 0.21 s
    assert d.check_heartbeat() and len(robot.moves("speedJ")) == 1
