"""The process client with a start configuration over two arms: roscore + `rosrun cell_nodes process_node` with a
cell file of two groups and `start_configuration: {left: home, right: home}`; this test stands in for the robot
driver's per-group state topics. at_start is true only while both arms are there."""
from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Iterator

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node
from test_process_node import HOME, Latest

UR = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
CELL = {
    "operation_mode": {"topic": "/cell/mode", "set_service": "/cell/set_mode", "modes": ["idle", "running", "alarm"]},
    "manual": {
        "groups": [{"name": "left", "host": "127.0.2.1", "joints": [f"left_{j}" for j in UR],
                    "configurations": {"home": HOME}},
                   # the right group names two of its arm's joints: only those count for at_start
                   {"name": "right", "host": "127.0.2.2", "joints": ["right_wrist_3_joint", "right_shoulder_pan_joint"],
                    "configurations": {"home": [0.5, -0.5]}}],
        "tools": [{"name": "vacuum", "group": "right", "actions": [{"name": "on", "steps": [{"digital_out": 4,
                                                                                            "value": True}]}]}]},
    "process": {"group": "left", "start_configuration": {"left": "home", "right": "home"},
                "operations": [{"name": "hand over", "steps": [{"move_named": "home"},
                                                               {"tool": "vacuum", "action": "on"}]}]},
}
RIGHT_HOME = [-0.5, 1.0, 1.0, 1.0, 1.0, 0.5]


@pytest.fixture(scope="module")
def client(roscore: str) -> Iterator[Nodes]:
    path = Path(tempfile.mkdtemp(prefix="process-twin-")) / "cell.yaml"
    path.write_text(yaml.safe_dump(CELL))
    client_node("process_twin_client_test")
    nodes = Nodes()
    nodes.run("process_node", "process_node", f"_cell_config:={path}", "__name:=process_twin_client")
    try:
        nodes.wait_ready("/cell/process/start", what="the process client")
        yield nodes
    finally:
        nodes.stop()
        nodes.check(within=5)


def test_at_start_follows_every_listed_group(client: Nodes) -> None:
    from cell_msgs.msg import ProcessState, RobotState
    state = Latest("/cell/process/state", ProcessState)
    pubs = {g: rospy.Publisher(f"/cell/manual/{g}/state", RobotState, queue_size=5) for g in ("left", "right")}
    try:
        wait_for(lambda: state.msg is not None, 5, what="the latched process state")
        assert state.msg.start_configuration == "left: home, right: home" and not state.msg.at_start
        wait_for(lambda: all(p.get_num_connections() > 0 for p in pubs.values()), 5,
                 what="the client subscribed to both groups' states")
        steps = (("left", HOME, False),                          # the right arm still unknown
                 ("right", RIGHT_HOME, True),                    # both there
                 ("right", [-0.5, 0, 0, 0, 0, 0.53], False),     # right's wrist 3 off by 0.03 rad
                 ("right", RIGHT_HOME, True),
                 ("left", [0.2] + HOME[1:], False))              # left's base away
        for group, joints, expected in steps:
            pubs[group].publish(RobotState(connected=True, motion_group=group, joint_positions=joints))
            wait_for(lambda: state.msg.at_start == expected, 3, what=f"at_start {expected} after {group} {joints}")
    finally:
        for p in pubs.values():
            p.unregister()
        state.sub.unregister()
