"""The alarms node keeps the mode an alarm replaced across its own restart (issue 28 "Nothing lost"): roscore + the
operation-mode node + `rosrun cell_nodes alarms_node` with its own DATA_DIR. The robot driver's state, a device fault
list and the module states come from this test's publishers. The node is killed (SIGKILL: no shutdown code runs,
as in a crash or a power cut) while the cell is in alarm, the fault clears meanwhile, and the restarted node gives
the mode back. A malformed state file is logged and the node starts clean."""
from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path
from typing import Any, Iterator, Optional

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Node, Nodes, client_node

ROOT = Path(__file__).resolve().parents[4]
FAULTS = "/alarms_restart_test/faults"
TAG = "alarms_restart_test"


class Latest:
    def __init__(self, topic: str, mtype: Any) -> None:
        self.msg: Any = None
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=50)

    def _cb(self, msg: Any) -> None:
        self.msg = msg


class Sources:
    """The robot driver's state at 10 Hz, a device fault list and the module states (both latched)."""

    def __init__(self) -> None:
        from cell_msgs.msg import AlarmList, ModuleStates, RobotState
        self.robot = rospy.Publisher("/cell/manual/arm/state", RobotState, queue_size=5)
        self.faults = rospy.Publisher(FAULTS, AlarmList, queue_size=5, latch=True)
        self.modules = rospy.Publisher("/cell/modules/state", ModuleStates, queue_size=5, latch=True)
        self.modules.publish(ModuleStates())
        self.fault(False)
        self._msg = RobotState(connected=True, controller="sim", robot_mode="RUNNING", safety_mode="NORMAL")
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.1):
            self.robot.publish(self._msg)

    def fault(self, active: bool) -> None:
        from cell_msgs.msg import Alarm, AlarmList
        self.faults.publish(AlarmList(alarms=[Alarm(id="door_open", text="Door open", severity=Alarm.ERROR,
                                                    active=active, since=rospy.Time.now())]))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        for pub in (self.robot, self.faults, self.modules):
            pub.unregister()


@pytest.fixture(scope="module")
def cell(roscore: str, tmp_path_factory) -> Iterator[dict]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    # No force supervision (no wrench source to stand in for); a short grace so a missed source cannot hold long.
    doc["alarms"] = {"fault_topics": [FAULTS], "timeout_s": 1, "startup_grace_s": 4}
    base = tmp_path_factory.mktemp("alarms-restart")
    path = base / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    data_dir = base / "data"
    env = dict(os.environ, DATA_DIR=str(data_dir), PYTHONUNBUFFERED="1")
    env.pop("CELL_CONFIG", None)
    client_node(f"{TAG}_client")
    mode = Nodes()
    mode_node = mode.run("operation_mode", "operation_mode_node", f"_cell_config:={path}", f"__name:={TAG}_mode",
                         env=env)
    sources = Sources()
    nodes: dict[str, Optional[Node]] = {"alarms": None}

    def start() -> Node:
        alarms = Nodes()
        node = nodes["alarms"] = alarms.run("alarms", "alarms_node", f"_cell_config:={path}", f"__name:={TAG}_alarms",
                                            env=env)
        alarms.wait_ready("/cell/alarms/reset", what="the alarms node's service")
        return node

    try:
        mode.wait_ready("/cell/set_mode", what="the operation-mode node")
        yield {"start": start, "sources": sources, "state_file": data_dir / "state" / "alarms.json", "nodes": nodes}
    finally:
        sources.close()
        ends = [n for n in (nodes["alarms"], mode_node) if n is not None]
        for node in ends:   # one after the other, the alarms node first
            node.stop()
        for node in ends:
            print(f"\n{node.label} log:\n{node.tail()}")
            node.check()


def test_the_mode_an_alarm_replaced_is_given_back_after_the_alarms_node_restarted(cell: dict) -> None:
    from cell_msgs.msg import OperationMode
    from cell_msgs.srv import SetMode
    mode = Latest("/cell/mode", OperationMode)
    try:
        node = cell["start"]()
        assert rospy.ServiceProxy("/cell/set_mode", SetMode)(mode="running", source="test").success
        wait_for(lambda: mode.msg is not None and mode.msg.mode == "running", 5, what="mode running")
        cell["sources"].fault(True)
        wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("alarm", "alarms"), 8, what="mode alarm")
        # On disk already when the switch was made (not at shutdown: a crash runs no shutdown code).
        saved = json.loads(cell["state_file"].read_text())
        assert (saved["kind"], saved["data"]["previous"], saved["data"]["seen"]) == (
            "alarms.mode", "running", ["device.door_open"])
        node.kill()
        cell["sources"].fault(False)                   # the door is closed while the alarms node is down
        time.sleep(0.5)
        assert (mode.msg.mode, mode.msg.source) == ("alarm", "alarms")
        node = cell["start"]()
        # Before this feature the restarted node had forgotten "running" and the cell stayed in alarm for good.
        wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("running", "alarms"), 10,
                 what=f"the mode given back (now {mode.msg.mode} from {mode.msg.source})")
        wait_for(lambda: "alarms state from" in node.output(), 3, what="the restore in the log")
        assert "mode to give back running" in node.output()
        wait_for(lambda: json.loads(cell["state_file"].read_text())["data"]["previous"] is None, 3,
                 what="the memory cleared on disk once given back")
    finally:
        mode.sub.unregister()


def test_a_malformed_state_file_is_logged_and_the_node_starts_clean(cell: dict) -> None:
    from cell_msgs.msg import OperationMode
    from cell_msgs.srv import SetMode
    node = cell["nodes"]["alarms"] or cell["start"]()
    node.stop()
    cell["nodes"]["alarms"] = None
    state_file: Path = cell["state_file"]
    state_file.write_text('{"kind": "alarms.mode", "version": 1, "data": {"previous": ')   # torn by hand
    mode = Latest("/cell/mode", OperationMode)
    try:
        node = cell["start"]()
        wait_for(lambda: "alarms state:" in node.output(), 5, what="the problem in the log")
        out = node.output()
        assert f"{state_file}: not valid JSON" in out and "starting clean" in out and f"{state_file}.bad" in out
        assert state_file.with_name("alarms.json.bad").exists()
        wait_for(lambda: state_file.exists(), 3, what="a clean state file")
        assert json.loads(state_file.read_text())["data"]["previous"] is None
        # The node works: an error alarm still switches the mode (and is remembered again).
        assert rospy.ServiceProxy("/cell/set_mode", SetMode)(mode="idle", source="test").success
        wait_for(lambda: mode.msg is not None and mode.msg.mode == "idle", 5, what="mode idle")
        cell["sources"].fault(True)
        wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("alarm", "alarms"), 8, what="mode alarm")
        wait_for(lambda: json.loads(state_file.read_text())["data"]["previous"] == "idle", 3, what="remembered")
        cell["sources"].fault(False)
        wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("idle", "alarms"), 8, what="mode back to idle")
    finally:
        mode.sub.unregister()
