"""The alarms node with two motion groups, on ROS 1 and ROS 2 (one body): `alarms_node` with a cell file of two groups
(left, right); this test stands in for the robot driver's per-group state topics through the nodes' wiring (no sim,
no operation-mode node: alarm_mode is off). Each group's alarms carry its name; one group silent raises only its own
no_state."""
from __future__ import annotations

import tempfile
import threading
from pathlib import Path
from typing import Iterator

import pytest
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, peer
from test_alarms_node import Latest, active

CELL = {
    "operation_mode": {"topic": "/cell/mode", "set_service": "/cell/set_mode", "modes": ["idle", "alarm"]},
    "manual": {"groups": [{"name": "left", "joints": ["left_elbow_joint"]},
                          {"name": "right", "joints": ["right_elbow_joint"]}]},
    "alarms": {"fault_topics": [], "timeout_s": 1, "startup_grace_s": 30, "alarm_mode": ""},
}


class Drivers:
    """Stands in for the driver: each group's RobotState at 10 Hz; a group can be silenced."""

    def __init__(self) -> None:
        from cell_msgs.msg import RobotState
        self.pubs = {g: peer().publisher(f"/cell/manual/{g}/state", RobotState, queue_size=5) for g in ("left", "right")}
        self.msgs = {g: RobotState(connected=True, controller=h, robot_mode="RUNNING", safety_mode="NORMAL",
                                   motion_group=g) for g, h in (("left", "127.0.2.1"), ("right", "127.0.2.2"))}
        self.silent: set[str] = set()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.1):
            for g, pub in self.pubs.items():
                if g not in self.silent:
                    pub.publish(self.msgs[g])

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2)
        for p in self.pubs.values():
            p.close()


@pytest.fixture(scope="module")
def node(ros_graph: str) -> Iterator[Drivers]:
    path = Path(tempfile.mkdtemp(prefix="alarms-twin-")) / "cell.yaml"
    path.write_text(yaml.safe_dump(CELL))
    nodes = Nodes()
    nodes.run("alarms_twin", "alarms_node", f"_cell_config:={path}", "__name:=alarms_twin_test")
    drivers = None
    try:
        nodes.wait_ready("/cell/alarms/reset", what="the alarms node")
        drivers = Drivers()
        yield drivers
    finally:
        if drivers:
            drivers.stop()
        nodes.stop()
        nodes.check()
        output = nodes.output("alarms_twin")
        assert "alarms from /cell/manual/left/state, /cell/manual/right/state" in output, output[-3000:]


def test_each_group_has_its_own_robot_alarms(node: Drivers) -> None:
    from cell_msgs.msg import AlarmList, SafetyStatus
    alarms = Latest("/cell/alarms/list", AlarmList)
    status = Latest("/cell/alarms/status", SafetyStatus)
    try:
        wait_for(lambda: status.msg is not None and status.msg.controller_connected, 10, what="both groups connected")
        node.msgs["right"].safety_mode = "PROTECTIVE_STOP"
        wait_for(lambda: active(alarms) == {"robot.right.protective_stop": True}, 3, what="the right arm's stop")
        (a,) = alarms.msg.alarms
        assert a.text == "Robot right: protective stop: the robot stopped; clear the cause, then unlock it"
        wait_for(lambda: status.msg.status == "protective stop" and status.msg.safety_mode == "PROTECTIVE_STOP", 3,
                 what="the status")
        node.msgs["right"].safety_mode = "NORMAL"
        node.silent.add("left")                                      # the left group's state stops
        wait_for(lambda: active(alarms) == {"robot.right.protective_stop": False, "robot.left.no_state": True}, 4,
                 what="left silent, right fine")
        # The list and the status are two topics: the status may reach this subscriber a moment after the list.
        wait_for(lambda: not status.msg.controller_connected and status.msg.status == "fault", 2,
                 what="the status says fault, not connected")
        node.silent.discard("left")
        wait_for(lambda: active(alarms).get("robot.left.no_state") is False and status.msg.controller_connected, 3,
                 what="left back")
    finally:
        alarms.sub.close()
        status.sub.close()
