"""The manual-motion node with a ros_control arm, end to end: roscore + the simulated KUKA iiwa driver (`python -m sim`,
sim/ros_control) + `rosrun cell_nodes manual_node`, both on one cell file: sim/tests/cells/iiwa-test.yaml (r7_ joints,
/r7/ topics, controller /r7/arm_controller, tip link r7_cup_face: none of config/iiwa-cell.yaml's names, so nothing
hard-coded passes) with named configurations and a vacuum tool added. The node reaches the arm only through the
driver's standard interfaces (joint states, FollowJointTrajectory, the command topic, robot_description, SetBool/Bool
IO); the tests watch the arm on the driver's own /r7/joint_states and the node on /cell/manual/arm/state.

Arm poses (cup pointing straight down, TCP in r7_link_0): HOME (0.55, 0, 0.30), the sim's start; TOUCH the cup face
2 mm above the cube at (0.55, 0.0); SIDE elsewhere.
The last test freezes the simulated driver (SIGSTOP): keep it last.
"""
from __future__ import annotations

import collections
import signal
import subprocess
import threading
import time
from pathlib import Path
from typing import Callable, Iterator, Optional

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node
from sim.tests.conftest import SimProcess, sim_env

TEST_CELL = Path(__file__).resolve().parents[4] / "sim" / "tests" / "cells" / "iiwa-test.yaml"
JOINTS = [f"r7_joint_{i}" for i in range(1, 8)]
CONTROLLER = "/r7/arm_controller"
HOME = [0.0, 0.5591, 0.0, -1.6245, 0.0, 0.958, 0.0]
SIDE = [0.3, 0.7, 0.0, -1.4, 0.0, 1.0, 0.2]
TOUCH = [0.0, 1.022, 0.0, -1.6199, 0.0, 0.4997, 0.0]  # the cup face 2 mm above the cube at (0.55, 0.0)
STILL = 0.01  # rad/s on every joint


def cell_doc() -> dict:
    """The test cell with what a manual_node cell has besides the driver's names: configurations, a tool, limits."""
    doc = yaml.safe_load(TEST_CELL.read_text(encoding="utf-8"))
    manual = doc["manual"]
    manual["groups"][0]["configurations"] = {"home": HOME, "side": SIDE, "touch": TOUCH}
    # The sim's cup: suction on io.outputs[2] (/r7/io/suction), "part held" on io.inputs[3] (/r7/io/part_held).
    manual["tools"] = [{"name": "vacuum", "group": "arm", "actions": [
        {"name": "on", "steps": [{"digital_out": 2, "value": True}, {"wait_input": 3, "value": True, "timeout_s": 1}]},
        {"name": "off", "steps": [{"digital_out": 2, "value": False}]}]}]
    manual.update(default_speed=0.5, default_acceleration=1.0, max_speed=1.0, max_acceleration=1.5,
                  max_tcp_speed=0.25, max_tcp_acceleration=1.0)
    return doc


class Latest:
    """The newest messages of a topic with their arrival times (our monotonic clock)."""

    def __init__(self, topic: str, mtype, keep: int = 2000) -> None:
        self.history: collections.deque = collections.deque(maxlen=keep)
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=200)

    def _cb(self, msg) -> None:
        with self._lock:
            self.history.append((time.monotonic(), msg))

    @property
    def msg(self):
        with self._lock:
            return self.history[-1][1] if self.history else None

    def after(self, t: float, predicate: Callable = lambda m: True):
        """The first message that arrived after `t` and satisfies `predicate`, else None."""
        with self._lock:
            return next((m for at, m in self.history if at > t and predicate(m)), None)

    def wait(self, predicate: Callable, timeout: float, what: str, since: float = -1.0):
        found: list = []
        wait_for(lambda: found.append(self.after(since, predicate)) or found[-1] is not None, timeout, 0.01, what)
        return found[-1]

    def speed(self, joint: int, t0: float, t1: float) -> float:
        """Mean velocity of a joint (rad/s) between the first messages that arrived after t0 and after t1."""
        with self._lock:
            a = next((at, m) for at, m in self.history if at > t0)
            b = [(at, m) for at, m in self.history if at <= t1][-1]
        dt = (b[1].header.stamp - a[1].header.stamp).to_sec()
        return (b[1].position[joint] - a[1].position[joint]) / dt

    def settled_at(self, since: float, still: Callable, hold: float = 0.1) -> Optional[float]:
        """Arrival time of the first message after `since` from which every message up to the newest satisfies
        `still`, once that run has lasted `hold` s; None before."""
        with self._lock:
            run: Optional[float] = None
            last = since
            for at, m in self.history:
                if at <= since:
                    continue
                run = (run if run is not None else at) if still(m) else None
                last = at
        return run if run is not None and last - run >= hold else None


def still(js) -> bool:
    return max(abs(v) for v in js.velocity) < STILL


def q_of(js) -> list[float]:
    pos = dict(zip(js.name, js.position))
    return [pos[n] for n in JOINTS]


def near(a, b, tol: float) -> bool:
    return max(abs(x - y) for x, y in zip(a, b)) < tol


class Stack:
    def __init__(self, sim: SimProcess, node: subprocess.Popen) -> None:
        from cell_msgs.msg import RobotState
        from geometry_msgs.msg import PoseStamped
        from sensor_msgs.msg import JointState
        self.sim, self.node = sim, node
        self.joints = Latest("/r7/joint_states", JointState)
        self.state = Latest("/cell/manual/arm/state", RobotState)
        self.pose = Latest("/cell/manual/arm/tcp_pose", PoseStamped)

    @staticmethod
    def call(service: str, stype, **kw):
        return rospy.ServiceProxy(f"/cell/manual/{service}", stype)(**kw)

    def fresh_q(self) -> list[float]:
        """The arm's joints from a joint state that arrived after now."""
        return q_of(self.joints.wait(lambda m: True, 2, "a fresh joint state", since=time.monotonic()))

    def home(self) -> None:
        from cell_msgs.srv import MoveNamed
        r = self.call("move_named", MoveNamed, group="arm", name="home", speed=1.0, acceleration=1.5)
        assert (r.success, r.message) == (True, "arrived at home")


def fault(name: str):
    from cell_msgs.srv import TriggerFault
    rospy.wait_for_service("/sim/trigger_fault", 5)
    r = rospy.ServiceProxy("/sim/trigger_fault", TriggerFault)(name)
    assert r.success, r.message
    return r


@pytest.fixture(scope="module")
def stack(roscore: str, tmp_path_factory) -> Iterator[Stack]:
    cell = tmp_path_factory.mktemp("iiwa") / "iiwa-manual.yaml"
    cell.write_text(yaml.safe_dump(cell_doc()), encoding="utf-8")
    sim = SimProcess("127.0.0.1", ["--cell", str(cell), "--no-cameras"], sim_env(roscore))
    nodes = Nodes()
    manual = nodes.run("manual_ros_control", "manual_node", f"_cell_config:={cell}", "__name:=manual_ros_control_test")
    try:
        client_node("manual_ros_control_client")
        s = Stack(sim, manual.proc)
        nodes.wait_ready("/cell/manual/stop")
        s.state.wait(lambda m: m.connected and m.robot_mode == "RUNNING", 30,
                     "the node connected to the simulated driver")
        yield s
        for rec in (s.joints, s.state, s.pose):
            rec.sub.unregister()
    finally:
        nodes.stop()
        if sim.proc.poll() is None:
            sim.proc.send_signal(signal.SIGCONT)  # the last test froze it
        sim_took = sim.stop()
        nodes.check(within=5)
        output = nodes.output("manual_ros_control")
        assert f"manual motion driver (ros_control) for {CONTROLLER}; groups: arm; tools: vacuum" in output, \
            output[-3000:]
        # 3 s: 2.07 s seen in CI with both cores busy
        assert sim_took < 3.0, f"the simulated driver took {sim_took:.2f} s to exit on SIGTERM"
        assert "Traceback" not in sim.output(), sim.output()[-3000:]


def test_state_groups_and_a_named_move(stack: Stack) -> None:
    from cell_msgs.srv import GetMotionGroups, GetPose, MoveNamed
    # The first connected state already says RUNNING: the node waits for the trajectory controller's action server
    # when it connects (else a moment of CONTROLLER_NOT_RUNNING, an error alarm, at every start).
    s = stack.state.wait(lambda m: m.connected, 5, "a connected state")
    assert (s.controller, s.motion_group, s.robot_mode, s.motion) == (CONTROLLER, "arm", "RUNNING", "idle")
    assert s.message == f"connected to the robot controller at {CONTROLLER}"
    assert len(s.joint_positions) == 7 and len(s.tcp_pose) == 6 and len(s.tcp_speed) == 6 and s.fault == ""
    assert near(s.joint_positions, HOME, 0.01)
    # The TCP from the driver's URDF (robot_description, r7_link_0 -> r7_cup_face): the cup over the table.
    assert near(s.tcp_pose[:3], [0.55, 0.0, 0.30], 0.005), s.tcp_pose
    pose = stack.pose.wait(lambda m: True, 2, "the TCP pose")
    assert pose.header.frame_id == "base" and abs(pose.pose.position.z - 0.30) < 0.005
    groups = stack.call("groups", GetMotionGroups)
    assert [g.name for g in groups.groups] == ["arm"] and list(groups.groups[0].joints) == JOINTS
    assert [c.name for c in groups.groups[0].configurations] == ["home", "side", "touch"]
    assert [(t.name, list(t.actions), t.group) for t in groups.tools] == [("vacuum", ["on", "off"], "arm")]

    r = stack.call("move_named", MoveNamed, group="arm", name="side", speed=1.0, acceleration=1.5)
    assert (r.success, r.message) == (True, "arrived at side")
    assert near(stack.fresh_q(), SIDE, 0.01)
    got = stack.call("get_pose", GetPose, group="arm")
    assert got.success and near(got.joint_positions, SIDE, 0.01) and len(got.tcp_pose) == 6
    assert stack.state.wait(lambda m: True, 1, "a state", since=time.monotonic()).message == "arrived at side"
    stack.home()
    assert near(stack.fresh_q(), HOME, 0.01)


def test_a_joint_jog_its_release_and_the_watchdog(stack: Stack) -> None:
    from cell_msgs.msg import JogCommand
    stack.home()
    jog = rospy.Publisher("/cell/manual/jog", JogCommand, queue_size=5)
    release = JogCommand(group="arm", mode="joint", axis=6, direction=0, speed=0.5, frame="base")
    try:
        wait_for(lambda: jog.get_num_connections() > 0, 5, what="the driver subscribed to the jog topic")
        # Hold J7 + for 0.7 s (heartbeats every 50 ms), then let go: direction 0.
        q0 = stack.fresh_q()[6]
        msg = JogCommand(group="arm", mode="joint", axis=6, direction=1, speed=0.5, frame="base")
        t0 = time.monotonic()
        while time.monotonic() < t0 + 0.7:
            jog.publish(msg)
            time.sleep(0.05)
        s = stack.state.msg
        assert (s.motion, s.motion_target) == ("jogging", "joint 7 +"), (s.motion, s.message)
        # At the commanded speed once it is reached (0.5 of max_speed 1.0 rad/s, streamed a few % under it), not
        # above it: the mean over the last 0.2 s.
        speed = stack.joints.speed(6, t0 + 0.5, time.monotonic())
        # (The stamps are the simulated driver's publish times: one message published late on a busy host shortens
        # the span by a few ms, which reads as up to ~1 % more speed; seen 0.523 in CI. 6 % over is a real overshoot.)
        assert 0.4 < speed < 0.53, speed
        released = time.monotonic()
        jog.publish(release)
        wait_for(lambda: stack.joints.settled_at(released, still) is not None, 2, 0.01, "standstill after the release")
        took = stack.joints.settled_at(released, still) - released
        print(f"\nstandstill {took:.3f} s after the release")
        assert took < 0.3
        moved = stack.fresh_q()[6] - q0
        assert moved > 0.15, moved
        stack.state.wait(lambda m: m.motion == "idle" and m.message == "jog stopped", 1, "the jog stopped",
                         since=released)

        # J7 - whose heartbeats stop: the driver's watchdog stops it (jog_timeout 0.2 s).
        q1 = stack.fresh_q()[6]
        msg.direction = -1
        end = time.monotonic() + 0.4
        while time.monotonic() < end:
            jog.publish(msg)
            last = time.monotonic()
            time.sleep(0.05)
        wait_for(lambda: stack.joints.settled_at(last, still) is not None, 2, 0.01, "standstill after the heartbeats")
        took = stack.joints.settled_at(last, still) - last
        print(f"standstill {took:.3f} s after the last heartbeat")
        assert took < 0.5
        stack.state.wait(lambda m: m.motion == "idle" and m.message == "jog stopped: no heartbeat for 0.2 s", 1,
                         "the watchdog's stop", since=last)
        assert stack.fresh_q()[6] - q1 < -0.1
        # Its heartbeats come again (a frozen page thawed, the button still held): nothing moves until a new press.
        q2 = stack.fresh_q()[6]
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            jog.publish(msg)
            time.sleep(0.05)
        assert stack.joints.settled_at(end - 0.5, still) is not None and abs(stack.fresh_q()[6] - q2) < 0.002, \
            "the stalled press moved the arm again"
        assert stack.state.msg.motion == "idle"
        jog.publish(release)
        start = time.monotonic()
        while time.monotonic() < start + 0.4:  # a new press (released, then pressed again) moves it
            jog.publish(msg)
            time.sleep(0.05)
        assert stack.fresh_q()[6] - q2 < -0.05
    finally:
        jog.publish(release)  # no jog left running for the next test, whatever failed
        jog.unregister()


def test_a_relative_move_and_an_unreachable_pose(stack: Stack) -> None:
    from cell_msgs.srv import GetPose, MovePose, MoveRelative
    stack.home()
    start = stack.call("get_pose", GetPose, group="arm").tcp_pose
    r = stack.call("move_relative", MoveRelative, group="arm", offset=[0, 0, 0.05, 0, 0, 0], frame="base", speed=0.1,
                   acceleration=0.5)
    assert (r.success, r.message) == (True, "arrived at the relative target")
    p = stack.pose.wait(lambda m: True, 2, "a TCP pose after the move", since=time.monotonic()).pose.position
    target = [start[0], start[1], start[2] + 0.05]
    assert near([p.x, p.y, p.z], target, 0.001), ([p.x, p.y, p.z], target)

    q0 = stack.fresh_q()
    t0 = time.monotonic()
    r = stack.call("move_pose", MovePose, group="arm", pose=[2.0, 0.0, 0.3, 3.14159, 0.0, 0.0], speed=0.1,
                   acceleration=0.5)
    assert not r.success and "unreachable" in r.message, r.message
    # Refused before anything was sent: the arm did not stir and stands where it stood.
    assert stack.joints.after(t0, lambda m: not still(m)) is None
    assert near(stack.fresh_q(), q0, 1e-3)
    assert stack.state.wait(lambda m: m.motion == "idle", 1, "idle", since=time.monotonic()).message == r.message


def test_a_blocked_arm_aborts_its_move_until_the_reset(stack: Stack) -> None:
    from cell_msgs.srv import MoveNamed
    stack.home()
    fault("collision")
    try:
        r = stack.call("move_named", MoveNamed, group="arm", name="side", speed=1.0, acceleration=1.5)
        assert not r.success and "PATH_TOLERANCE_VIOLATED" in r.message, r.message
        assert r.message.startswith("the controller aborted the trajectory: PATH_TOLERANCE_VIOLATED"), r.message
        s = stack.state.wait(lambda m: m.fault != "", 2, "the fault in the driver state")
        assert s.fault == r.message and s.motion == "idle"
        # still refused while the arm is blocked, with the same fault
        r2 = stack.call("move_named", MoveNamed, group="arm", name="side", speed=1.0, acceleration=1.5)
        assert not r2.success and "PATH_TOLERANCE_VIOLATED" in r2.message, r2.message
    finally:
        fault("reset")
    r = stack.call("move_named", MoveNamed, group="arm", name="side", speed=1.0, acceleration=1.5)
    assert (r.success, r.message) == (True, "arrived at side")
    assert near(stack.fresh_q(), SIDE, 0.01)
    assert stack.state.wait(lambda m: True, 1, "a state", since=time.monotonic()).fault == ""


def test_the_vacuum_over_nothing_and_over_a_part(stack: Stack) -> None:
    from cell_msgs.srv import MoveNamed, ToolAction
    from std_msgs.msg import Bool
    stack.home()  # the cup 0.26 m above the table: nothing to hold
    held = Latest("/r7/io/part_held", Bool)
    try:
        t0 = time.monotonic()
        r = stack.call("tool", ToolAction, tool="vacuum", action="on")
        took = time.monotonic() - t0
        assert (r.success, r.message) == (False, "vacuum on: digital input 3 did not turn on within 1 s")
        assert 1.0 <= took < 2.0, took
        assert held.after(t0, lambda m: m.data) is None
        s = stack.state.wait(lambda m: m.motion == "idle", 1, "idle", since=time.monotonic())
        assert s.message == r.message
        r = stack.call("tool", ToolAction, tool="vacuum", action="off")
        assert (r.success, r.message) == (True, "vacuum off done")

        # Over a part the same action succeeds: the output and the input are the driver's SetBool and Bool.
        r = stack.call("move_named", MoveNamed, group="arm", name="touch", speed=1.0, acceleration=1.5)
        assert (r.success, r.message) == (True, "arrived at touch")
        t1 = time.monotonic()
        r = stack.call("tool", ToolAction, tool="vacuum", action="on")
        assert (r.success, r.message) == (True, "vacuum on done")
        assert held.after(t1, lambda m: m.data) is not None
        r = stack.call("tool", ToolAction, tool="vacuum", action="off")
        assert (r.success, r.message) == (True, "vacuum off done")
        held.wait(lambda m: not m.data, 1, "the part let go", since=time.monotonic())
    finally:
        held.sub.unregister()
    stack.home()


def test_a_driver_that_stops_answering(stack: Stack) -> None:
    from cell_msgs.srv import GetPose, MoveNamed
    stack.home()
    stack.sim.proc.send_signal(signal.SIGSTOP)  # the arm's driver hangs: no joint states, no action status
    t0 = time.monotonic()
    try:
        s = stack.state.wait(lambda m: not m.connected, 3, "the state disconnected", since=t0)
        assert s.robot_mode == "NO_CONTROLLER"
        s = stack.state.wait(lambda m: "/r7/joint_states" in m.message, 6, "a message naming the joint states",
                             since=t0)
        assert not s.connected
        assert s.message == (f"robot controller at {CONTROLLER} is unreachable: no joint states on /r7/joint_states "
                             f"(is the arm's driver running?)"), s.message
        print(f"\nthe joint states named {time.monotonic() - t0:.2f} s after the driver froze")
        r = stack.call("move_named", MoveNamed, group="arm", name="side", speed=1.0, acceleration=1.5)
        assert (r.success, r.message) == (False, f"robot controller at {CONTROLLER} is unreachable")
        got = stack.call("get_pose", GetPose, group="arm")
        assert (got.success, got.message) == (False, f"robot controller at {CONTROLLER} is unreachable")
        assert stack.node.poll() is None
    finally:
        stack.sim.proc.send_signal(signal.SIGCONT)
    # The driver answers again: the node reconnects by itself and moves.
    t1 = time.monotonic()
    s = stack.state.wait(lambda m: m.connected, 10, "reconnected", since=t1)
    # Connected means its controller answers too: no CONTROLLER_NOT_RUNNING blip (an error alarm) on the way.
    assert (s.robot_mode, s.message) == ("RUNNING", f"reconnected to the robot controller at {CONTROLLER}")
    r = stack.call("move_named", MoveNamed, group="arm", name="side", speed=1.0, acceleration=1.5)
    assert (r.success, r.message) == (True, "arrived at side")
