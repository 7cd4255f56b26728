"""The manual-motion node with two arms: roscore + two simulated controllers (127.0.3.21, 127.0.3.22, each the demo
sim's single arm) + `rosrun cell_nodes manual_node` with a cell file of two groups (left: gripper, right: vacuum)
whose hosts come from UR_HOSTS, as several stacks of one cell run side by side. One driver per arm: per-group state
and pose topics, /joint_states with each arm's own joint names, requests routed by group and tools by their group,
a jog moving only its arm, and one stop that stops both."""
from __future__ import annotations

import os
import subprocess
import threading
import time
from typing import Iterator

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node
from sim.tests.conftest import SimProcess, sim_env

LEFT, RIGHT = "127.0.3.21", "127.0.3.22"
UR = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
HOME = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]
APPROACH = [0.4, -1.2, 1.6, -1.97, -1.5708, 0.4]
CELL = {"manual": {
    "groups": [
        # the file's hosts are not these sims': UR_HOSTS overrides them (as the tests of a stack do)
        {"name": "left", "host": "127.0.2.1", "joints": [f"left_{j}" for j in UR],
         "configurations": {"home": HOME, "approach": APPROACH}},
        {"name": "right", "host": "127.0.2.2", "joints": [f"right_{j}" for j in UR],
         "configurations": {"home": HOME, "approach": APPROACH}},
    ],
    "tools": [
        {"name": "gripper", "actions": [
            {"name": "close", "steps": [{"digital_out": 0, "value": True}, {"wait_input": 1, "value": True}]},
            {"name": "open", "steps": [{"digital_out": 0, "value": False}, {"wait_input": 1, "value": False}]}]},
        {"name": "vacuum", "group": "right", "actions": [
            {"name": "on", "steps": [{"digital_out": 4, "value": True}]},
            {"name": "off", "steps": [{"digital_out": 4, "value": False}]}]},
    ],
    "default_speed": 0.25, "default_acceleration": 0.5, "max_speed": 1.0, "max_acceleration": 1.5,
}}


class Latest:
    def __init__(self, topic: str, mtype) -> None:
        self.msg = None
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=50)

    def _cb(self, msg) -> None:
        self.msg = msg


class Joints:
    """/joint_states from both arms, kept apart by their names."""

    def __init__(self) -> None:
        from sensor_msgs.msg import JointState
        self.by_arm: dict[str, object] = {}
        self.sub = rospy.Subscriber("/joint_states", JointState, self._cb, queue_size=500)

    def _cb(self, msg) -> None:
        self.by_arm[msg.name[0].split("_")[0]] = msg

    def q(self, arm: str) -> list[float]:
        return list(self.by_arm[arm].position)  # type: ignore[attr-defined]

    def still(self, arm: str) -> bool:
        return max(abs(v) for v in self.by_arm[arm].velocity) < 0.01  # type: ignore[attr-defined]


def near(a, b, tol: float = 0.01) -> bool:
    return max(abs(x - y) for x, y in zip(a, b)) < tol


@pytest.fixture(scope="module")
def node(roscore: str, tmp_path_factory) -> Iterator[subprocess.Popen]:
    cell_file = tmp_path_factory.mktemp("twin") / "twin.yaml"
    cell_file.write_text(yaml.safe_dump(CELL))
    sims = []
    nodes = Nodes()
    try:
        sims = [SimProcess(h, ["--no-ros", "--no-cameras"], sim_env()) for h in (LEFT, RIGHT)]  # side by side
        for s in sims:
            s.wait_ready()
        env = dict(os.environ, UR_HOSTS=f"left={LEFT}, right={RIGHT}")
        env.pop("UR_HOST", None)
        manual = nodes.run("manual_twin", "manual_node", f"_cell_config:={cell_file}", "__name:=manual_twin_test",
                           env=env)
        client_node("manual_twin_client")
        nodes.wait_ready("/cell/manual/stop")
        yield manual.proc
    finally:
        nodes.stop()
        for s in sims:
            s.stop()
        nodes.check(within=5)
        output = nodes.output("manual_twin")
        assert f"UR controller at {LEFT}; groups: left; tools: gripper" in output, output[-3000:]
        assert f"UR controller at {RIGHT}; groups: right; tools: vacuum" in output, output[-3000:]


def test_two_arms_through_one_node(node) -> None:
    import rtde_receive
    from cell_msgs.msg import JogCommand, RobotState
    from cell_msgs.srv import GetMotionGroups, GetPose, MoveNamed, ToolAction
    from geometry_msgs.msg import PoseStamped
    from std_srvs.srv import Trigger

    joints = Joints()
    state = {g: Latest(f"/cell/manual/{g}/state", RobotState) for g in ("left", "right")}
    pose = {g: Latest(f"/cell/manual/{g}/tcp_pose", PoseStamped) for g in ("left", "right")}
    wait_for(lambda: all(s.msg is not None and s.msg.connected for s in state.values())
             and set(joints.by_arm) == {"left", "right"} and all(p.msg for p in pose.values()), 15,
             what="both arms' topics, connected")
    for g, host in (("left", LEFT), ("right", RIGHT)):
        s = state[g].msg
        assert (s.controller, s.motion_group, s.robot_mode, s.motion) == (host, g, "RUNNING", "idle")
        assert list(joints.by_arm[g].name) == [f"{g}_{j}" for j in UR]  # type: ignore[attr-defined]
    topics = {name for name, _ in rospy.get_published_topics()}
    assert "/cell/manual/state" not in topics and "/cell/manual/left/tcp_pose" in topics

    groups = rospy.ServiceProxy("/cell/manual/groups", GetMotionGroups)()
    assert [g.name for g in groups.groups] == ["left", "right"]
    assert list(groups.groups[1].joints) == [f"right_{j}" for j in UR]
    assert [(t.name, t.group) for t in groups.tools] == [("gripper", "left"), ("vacuum", "right")]

    # A move of the right arm moves only the right arm.
    move = rospy.ServiceProxy("/cell/manual/move_named", MoveNamed)
    left_q = joints.q("left")
    r = move(group="right", name="approach", speed=1.0, acceleration=1.5)
    assert (r.success, r.message) == (True, "arrived at approach")
    assert near(joints.q("right"), APPROACH) and near(joints.q("left"), left_q, 1e-3)
    got = rospy.ServiceProxy("/cell/manual/get_pose", GetPose)(group="right")
    assert got.success and near(got.joint_positions, APPROACH)
    assert near(rospy.ServiceProxy("/cell/manual/get_pose", GetPose)(group="left").joint_positions, left_q, 1e-3)
    bad = rospy.ServiceProxy("/cell/manual/get_pose", GetPose)(group="middle")
    assert (bad.success, bad.message) == (False, "unknown motion group 'middle' (the cell has: left, right)")

    # Tools on their group's controller: the vacuum's DO4 on the right one, the gripper's DO0 on the left one.
    left_io, right_io = rtde_receive.RTDEReceiveInterface(LEFT), rtde_receive.RTDEReceiveInterface(RIGHT)
    try:
        tool = rospy.ServiceProxy("/cell/manual/tool", ToolAction)
        r = tool(tool="vacuum", action="on")
        assert (r.success, r.message) == (True, "vacuum on done")
        r = tool(tool="gripper", action="close")
        assert (r.success, r.message) == (True, "gripper close done")
        wait_for(lambda: right_io.getActualDigitalOutputBits() & 0b10001 == 0b10000
                 and left_io.getActualDigitalOutputBits() & 0b10001 == 0b00001, 2, what="each arm's outputs")
        assert tool(tool="vacuum", action="off").success and tool(tool="gripper", action="open").success
    finally:
        left_io.disconnect()
        right_io.disconnect()

    # A jog over the topic moves its group's arm only; its own dead-man timeout stops it.
    jog = rospy.Publisher("/cell/manual/jog", JogCommand, queue_size=5)
    wait_for(lambda: jog.get_num_connections() > 0, 5, what="the driver subscribed to the jog topic")
    right_q, q5 = joints.q("right"), joints.q("left")[5]
    end = time.monotonic() + 0.5
    while time.monotonic() < end:
        jog.publish(JogCommand(group="left", mode="joint", axis=5, direction=1, speed=0.5, frame="base"))
        time.sleep(0.05)
    assert state["left"].msg.motion == "jogging" and state["right"].msg.motion == "idle"
    wait_for(lambda: state["left"].msg.motion == "idle" and joints.still("left"), 2, what="the jog stopped")
    assert state["left"].msg.message == "jog stopped: no heartbeat for 0.2 s"
    # (the left arm's first motion command: its control script starts first, so the jog is short on a busy machine)
    assert joints.q("left")[5] - q5 > 0.02 and near(joints.q("right"), right_q, 1e-3)
    jog.unregister()

    # One stop stops both arms, each in the middle of its move.
    answers: dict[str, object] = {}
    movers = [threading.Thread(target=lambda g=g, n=n: answers.setdefault(g, move(group=g, name=n, speed=0.2,
                                                                                   acceleration=1.0)))
              for g, n in (("left", "approach"), ("right", "home"))]
    for t in movers:
        t.start()
    wait_for(lambda: all(s.msg.motion == "moving" and s.msg.progress > 0.1 for s in state.values()), 5,
             what="both arms moving")
    t0 = time.monotonic()
    r = rospy.ServiceProxy("/cell/manual/stop", Trigger)()
    took = time.monotonic() - t0
    assert (r.success, r.message) == (True, "stopped")
    for t in movers:
        t.join(5)
    assert {g: (a.success, a.message) for g, a in answers.items()} == {  # type: ignore[attr-defined]
        "left": (False, "stopped"), "right": (False, "stopped")}
    wait_for(lambda: joints.still("left") and joints.still("right"), 1, what="both arms standing still")
    assert not near(joints.q("left"), APPROACH, 0.05) and not near(joints.q("right"), HOME, 0.05)
    print(f"\nstop of both arms answered in {took:.2f} s")
    assert took < 1.5
    joints.sub.unregister()
    for rec in (*state.values(), *pose.values()):
        rec.sub.unregister()
