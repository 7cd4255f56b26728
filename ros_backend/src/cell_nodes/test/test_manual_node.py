"""The manual-motion node end to end: roscore + the simulated controller + `rosrun cell_nodes manual_node`, used
over ROS the way the BFF relays the page's calls (services, the jog topic) and watched on its topics."""
from __future__ import annotations

import math
import subprocess
import threading
import time
from pathlib import Path
from typing import Iterator

import pytest
import rospy

from conftest import wait_for
from nodes_helpers import Nodes, client_node, start_sim

HOST = "127.0.0.53"
CELL = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"
UR_JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
             "wrist_3_joint"]


class Latest:
    """Keeps the newest message of a topic and when messages arrived."""

    def __init__(self, topic: str, mtype) -> None:
        self.msg = None
        self.times: list[float] = []
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=200)

    def _cb(self, msg) -> None:
        with self._lock:
            self.msg = msg
            self.times.append(time.monotonic())

    def rate(self, window: float = 1.0) -> float:
        with self._lock:
            t = [x for x in self.times if x > self.times[-1] - window]
        return (len(t) - 1) / (t[-1] - t[0]) if len(t) > 2 else 0.0


@pytest.fixture(scope="module")
def node(roscore: str) -> Iterator[subprocess.Popen]:
    sim = start_sim(HOST, "--no-ros", "--no-cameras")
    nodes = Nodes()
    manual = nodes.run("manual", "manual_node", f"_cell_config:={CELL}", f"_ur_host:={HOST}", "__name:=manual_test")
    try:
        client_node("manual_test_client")
        nodes.wait_ready("/cell/manual/stop")
        yield manual.proc
    finally:
        nodes.stop()
        sim.stop()
        nodes.check(within=5)


def test_services_topics_and_a_jog_through_ros(node) -> None:
    from cell_msgs.msg import JogCommand, RobotState
    from cell_msgs.srv import GetMotionGroups, GetPose, MoveNamed, MoveRelative, ToolAction
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import JointState
    from std_srvs.srv import Trigger

    joints = Latest("/joint_states", JointState)
    state = Latest("/cell/manual/arm/state", RobotState)
    pose = Latest("/cell/manual/arm/tcp_pose", PoseStamped)
    wait_for(lambda: state.msg is not None and state.msg.connected and joints.msg and pose.msg, 10,
             what="the driver's topics, connected")
    s = state.msg
    assert (s.controller, s.robot_mode, s.safety_mode, s.program_running) == (HOST, "RUNNING", "NORMAL", False)
    assert len(s.joint_positions) == 6 and len(s.tcp_pose) == 6 and len(s.tcp_speed) == 6
    assert s.message == f"connected to the robot controller at {HOST}" and s.motion == "idle"
    assert (s.message_code, [(kv.key, kv.value) for kv in s.message_params]) == ("manual.connected", [("host", HOST)])
    assert s.motion_group == "arm"                      # the topic's group
    topics = {name for name, _ in rospy.get_published_topics()}
    assert "/cell/manual/state" not in topics and "/cell/manual/tcp_pose" not in topics
    assert list(joints.msg.name) == UR_JOINTS and len(joints.msg.velocity) == 6
    assert pose.msg.header.frame_id == "base"
    time.sleep(1.0)  # a one-second window to measure the publication rates in (nothing to wait for)
    print(f"\n/joint_states at {joints.rate():.0f} Hz, /cell/manual/arm/state at {state.rate():.0f} Hz")
    assert joints.rate() > 80 and 15 < state.rate() < 40

    groups = rospy.ServiceProxy("/cell/manual/groups", GetMotionGroups)()
    assert [g.name for g in groups.groups] == ["arm"] and list(groups.groups[0].joints) == UR_JOINTS
    assert [c.name for c in groups.groups[0].configurations] == ["home", "pick_approach"]
    assert [(t.name, list(t.actions), t.group) for t in groups.tools] == [
        ("gripper", ["open", "close", "check_part"], "arm")]
    assert groups.limits.max_tcp_speed == 0.25 and groups.limits.jog_timeout == pytest.approx(0.2)

    move_named = rospy.ServiceProxy("/cell/manual/move_named", MoveNamed)
    r = move_named(group="arm", name="home", speed=1.0, acceleration=1.5)
    assert (r.success, r.message, r.code, [(kv.key, kv.value) for kv in r.params]) == (
        True, "arrived at home", "manual.arrived_at", [("name", "home")])
    got = rospy.ServiceProxy("/cell/manual/get_pose", GetPose)(group="arm")
    assert got.success and max(abs(a - b) for a, b in zip(got.joint_positions, [0.0, -1.5708, 1.5708, -1.5708,
                                                                                 -1.5708, 0.0])) < 0.01
    r = rospy.ServiceProxy("/cell/manual/move_relative", MoveRelative)(
        group="arm", offset=[0, 0, 0.03, 0, 0, 0], frame="base", speed=0.1, acceleration=0.5)
    assert r.success, r.message
    assert abs(rospy.ServiceProxy("/cell/manual/get_pose", GetPose)(group="arm").tcp_pose[2] - got.tcp_pose[2]
               - 0.03) < 0.001
    r = move_named(group="arm", name="nowhere", speed=0, acceleration=0)
    assert not r.success and r.message.startswith("unknown configuration 'nowhere'")
    assert r.code == "manual.unknown_configuration" and ("name", "nowhere") in [(kv.key, kv.value) for kv in r.params]
    r = rospy.ServiceProxy("/cell/manual/tool", ToolAction)(tool="gripper", action="close")
    assert (r.success, r.message) == (True, "gripper close done")
    wait_for(lambda: state.msg.message == "gripper close done", 2, what="the result in the state")

    # Hold-to-run over the topic: jog wrist 3 with 50 ms heartbeats, then let go of the "button".
    jog = rospy.Publisher("/cell/manual/jog", JogCommand, queue_size=5)
    wait_for(lambda: jog.get_num_connections() > 0, 5, what="the driver subscribed to the jog topic")
    q0 = joints.msg.position[5]
    msg = JogCommand(group="arm", mode="joint", axis=5, direction=1, speed=0.5, frame="base")
    end = time.monotonic() + 0.6
    while time.monotonic() < end:
        jog.publish(msg)
        time.sleep(0.05)
    assert state.msg.motion == "jogging" and state.msg.motion_target == "joint 6 +"
    assert abs(joints.msg.velocity[5] - 0.5) < 0.05
    wait_for(lambda: state.msg.motion == "idle" and max(abs(v) for v in joints.msg.velocity) < 0.01, 2,
             what="standstill after the heartbeats stopped")
    assert state.msg.message == "jog stopped: no heartbeat for 0.2 s"
    assert (state.msg.message_code, [(kv.key, kv.value) for kv in state.msg.message_params]) == (
        "manual.jog_no_heartbeat", [("seconds", "0.2")])
    assert joints.msg.position[5] - q0 > 0.2
    r = rospy.ServiceProxy("/cell/manual/stop", Trigger)()
    assert (r.success, r.message) == (True, "stopped")
    for rec in (joints, state, pose):
        rec.sub.unregister()
    assert not math.isnan(joints.msg.position[0])


def test_preview_move_through_ros(node) -> None:
    """/cell/manual/preview_move: a named configuration's target is the cell file's values, nothing moves."""
    import yaml
    from cell_msgs.srv import PreviewMove

    configs = yaml.safe_load(CELL.read_text())["manual"]["groups"][0]["configurations"]
    preview = rospy.ServiceProxy("/cell/manual/preview_move", PreviewMove)
    r = preview(group="arm", kind="named", name="pick_approach")
    assert (r.reachable, r.message, list(r.joint_names)) == (True, "pick_approach is reachable", UR_JOINTS)
    assert list(r.positions) == configs["pick_approach"] and len(r.tcp_pose) == 6
    r = preview(group="arm", kind="jump")
    assert (r.reachable, r.message, list(r.positions)) == (False, "unknown move kind 'jump' (named, relative or pose)",
                                                          [])
    assert (r.code, [(kv.key, kv.value) for kv in r.params]) == ("manual.unknown_kind", [("kind", "jump")])


def test_the_driver_reports_its_controller_link_and_joint_state_rate_on_diagnostics(node) -> None:
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    diag = Latest("/diagnostics", DiagnosticArray)
    try:
        def mine():
            return next((s for s in diag.msg.status if s.name == "manual_test: arm controller"), None) \
                if diag.msg else None
        # The first report after a second of joint states (the rate is over the last 2 s).
        wait_for(lambda: mine() is not None and float(dict((kv.key, kv.value) for kv in mine().values)
                                                      ["joint states (Hz)"]) > 60, 5, what="the driver's diagnostics")
        s = mine()
        values = {kv.key: kv.value for kv in s.values}
        assert (s.level, s.message) == (DiagnosticStatus.OK, "connected")
        assert values["controller"] == HOST and values["safety mode"] == "NORMAL" and values["expected (Hz)"] == "125"
    finally:
        diag.sub.unregister()
