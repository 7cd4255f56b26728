"""The alarms node end to end on a live ROS graph, one body for both generations (scripts/test-all.sh runs this file
under .venv-ros2 too): the operation-mode node + `alarms_node`. The robot driver's state, a device's faults, the wrist
wrench and the modules' states come from this test's own publishers through the nodes' wiring (the simulated cell's
faults reach the node in the e2e alarms spec)."""
from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any, Iterator

import pytest
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, peer

HOST = "127.0.0.61"
ROOT = Path(__file__).resolve().parents[4]
WRENCH = "/alarms_test/wrench"
FAULTS = "/alarms_test/faults"


class Latest:
    """Keeps the newest message of a topic."""

    def __init__(self, topic: str, mtype: type, latched: bool = True) -> None:
        self.msg: Any = None
        self.count = 0
        self.sub = peer().subscribe(topic, mtype, self._cb, queue_size=50, latched=latched)

    def _cb(self, msg: Any, _sender: str) -> None:
        self.msg = msg
        self.count += 1


class Driver:
    """Stands in for the robot driver: publishes cell_msgs/RobotState at 10 Hz until stopped."""

    def __init__(self) -> None:
        from cell_msgs.msg import RobotState
        self.pub = peer().publisher("/cell/manual/arm/state", RobotState, queue_size=5)
        self.msg = RobotState(connected=True, controller=HOST, robot_mode="RUNNING", safety_mode="NORMAL")
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(0.1):
            self.pub.publish(self.msg)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2)
        self.pub.close()


class Device:
    """Stands in for a device's fault topic (latched cell_msgs/AlarmList, as the simulated cell's /sim/faults)."""

    def __init__(self) -> None:
        from cell_msgs.msg import AlarmList
        self.pub = peer().publisher(FAULTS, AlarmList, latch=True, queue_size=5)
        self.set(active=None)

    def set(self, active: bool | None, since: float = 0.0) -> None:
        from cell_msgs.msg import Alarm, AlarmList
        out = AlarmList()
        if active is not None:
            out.alarms = [Alarm(id="gripper_fault", text="Gripper fault: the jaws are jammed", severity=2,
                                active=active, since=peer().stamp(since))]
        self.pub.publish(out)


@pytest.fixture(scope="module")
def cell(ros_graph: str, tmp_path_factory: Any) -> Iterator[dict]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["alarms"] = {"force_limit_n": 80, "wrench_topics": [WRENCH], "fault_topics": [FAULTS], "timeout_s": 1}
    path = tmp_path_factory.mktemp("alarms") / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    nodes = Nodes()
    nodes.run("operation_mode", "operation_mode_node", f"_cell_config:={path}", "__name:=operation_mode_alarms_test")
    node = nodes.run("alarms", "alarms_node", f"_cell_config:={path}", "__name:=alarms_test")
    driver = device = None
    try:
        nodes.wait_ready("/cell/alarms/reset", "/cell/set_mode", what="the nodes' services")
        driver, device = Driver(), Device()
        yield {"path": path, "driver": driver, "device": device, "log": str(node.log_path)}
    finally:
        if driver:
            driver.stop()
        if device:
            device.pub.close()
        nodes.stop()
        nodes.check()


def active(rec: Latest) -> dict[str, bool]:
    return {a.id: a.active for a in rec.msg.alarms} if rec.msg else {}


def test_faults_become_alarms_switch_the_mode_and_reset_clears_them(cell) -> None:
    from cell_msgs.msg import AlarmList, ModuleState, ModuleStates, OperationMode, SafetyStatus
    from cell_msgs.srv import SetMode
    from geometry_msgs.msg import WrenchStamped
    from std_srvs.srv import Trigger

    ros = peer()
    alarms = Latest("/cell/alarms/list", AlarmList)
    status = Latest("/cell/alarms/status", SafetyStatus)
    mode = Latest("/cell/mode", OperationMode)
    reset = ros.client("/cell/alarms/reset", Trigger)
    wait_for(lambda: status.msg and status.msg.controller_connected and mode.msg, 10, what="status with the driver")
    assert (status.msg.status, status.msg.safety_mode, status.msg.robot_mode) == ("normal", "NORMAL", "RUNNING")
    assert list(alarms.msg.alarms) == [] and status.msg.highest_severity == -1
    assert ros.client("/cell/set_mode", SetMode)(mode="running", source="test").success
    wait_for(lambda: mode.msg.mode == "running", 5, what="mode running")

    # A device fault: an active error alarm, and the operation mode goes to alarm.
    t0 = time.time()
    cell["device"].set(active=True, since=t0)
    wait_for(lambda: active(alarms) == {"device.gripper_fault": True}, 5, what="gripper fault alarm")
    (a,) = alarms.msg.alarms
    assert (a.severity, a.source, a.count) == (2, "device", 1) and "Gripper fault" in a.text
    assert t0 - 1 < ros.seconds(a.since) <= ros.seconds(a.last_seen)
    wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("alarm", "alarms"), 5, what="mode alarm")
    wait_for(lambda: status.msg.status == "fault" and status.msg.active_count == 1, 3, what="status fault")
    assert status.msg.text == a.text and status.msg.highest_severity == 2

    # Cleared at the device: inactive (still listed), and the mode goes back to what it was.
    cell["device"].set(active=False, since=t0)
    wait_for(lambda: active(alarms) == {"device.gripper_fault": False}, 5, what="inactive alarm")
    wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("running", "alarms"), 5, what="mode back to running")
    wait_for(lambda: (status.msg.status, status.msg.active_count, status.msg.inactive_count) == ("normal", 0, 1),
             3, what="status normal with one inactive alarm")

    # The robot in a protective stop: reset keeps it (its cause is still there); the inactive one goes.
    cell["driver"].msg.safety_mode = "PROTECTIVE_STOP"
    wait_for(lambda: status.msg.status == "protective stop", 3, what="protective stop status")
    r = reset()
    assert r.success and r.message == "cleared 1 inactive alarm (device.gripper_fault); " \
                                      "1 still active (robot.arm.protective_stop)"
    wait_for(lambda: active(alarms) == {"robot.arm.protective_stop": True}, 3, what="only the active alarm left")
    # Its code and parameters go out with it, for the app to say it in the user's language.
    stop = alarms.msg.alarms[0]
    assert (stop.code, [(p.key, p.value) for p in stop.params]) == ("robot.safety.protective_stop", [("group", "arm")])
    assert (status.msg.alarm_id, status.msg.code, [(p.key, p.value) for p in status.msg.params]) == \
        ("robot.arm.protective_stop", "robot.safety.protective_stop", [("group", "arm")])

    # A late subscriber gets the current list at once: latched (transient local on ROS 2).
    late = Latest("/cell/alarms/list", AlarmList)
    wait_for(lambda: late.msg is not None, 10, what="the latched list for a late subscriber")
    assert [(x.id, x.active) for x in late.msg.alarms] == [("robot.arm.protective_stop", True)]
    late.sub.close()

    cell["driver"].msg.safety_mode = "NORMAL"
    wait_for(lambda: active(alarms) == {"robot.arm.protective_stop": False}, 3, what="protective stop gone")
    wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("running", "alarms"), 5, what="mode back again")

    # The wrist force above the limit (norm 85 N, no single axis above 80 N), sent until the node has heard it.
    wrench = ros.publisher(WRENCH, WrenchStamped, queue_size=5)
    msg = WrenchStamped()
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = 60.0, 60.0, -5.0
    wait_for(lambda: wrench.publish(msg) and active(alarms).get("force.limit") is True, 5, 0.1,
             what="force limit alarm")
    msg.wrench.force.x, msg.wrench.force.y = 10.0, 0.0
    wrench.publish(msg)
    wait_for(lambda: active(alarms).get("force.limit") is False, 3, what="force back under the limit")
    assert reset().message.startswith("cleared 2 inactive alarms")

    # A module that became incomplete (the modules node's latched state).
    modules = ros.publisher("/cell/modules/state", ModuleStates, latch=True, queue_size=5)
    modules.publish(ModuleStates(modules=[ModuleState(name="vision", state="incomplete", nodes=["/cam", "/det"],
                                                      alive=[True, False], message="not running: /det")]))
    wait_for(lambda: active(alarms).get("module.vision") is True, 5, what="incomplete module alarm")
    assert [a.text for a in alarms.msg.alarms if a.id == "module.vision"] == \
        ["module vision is incomplete: not running: /det"]
    assert mode.msg.mode == "running"                      # a warning does not switch the mode
    modules.publish(ModuleStates(modules=[ModuleState(name="vision", state="active")]))
    wait_for(lambda: active(alarms).get("module.vision") is False, 3, what="module complete again")
    modules.close()

    # The driver falls silent (timeout_s 1): an error alarm, the controller counts as not connected.
    cell["driver"].stop()
    wait_for(lambda: active(alarms).get("robot.arm.no_state") is True, 4, what="no robot state alarm")
    wait_for(lambda: not status.msg.controller_connected and status.msg.status == "fault", 3, what="status")
    assert (status.msg.safety_mode, status.msg.robot_mode) == ("", "")
    wait_for(lambda: mode.msg.mode == "alarm", 5, what="mode alarm for the silent driver")
    # The wrench stopped too: its warning is there.
    assert active(alarms).get("force.no_data") is True
    wrench.close()
    for rec in (alarms, status, mode):
        rec.sub.close()
