"""The alarms node end to end: roscore + the operation-mode node + the simulated cell (its /sim/faults and
/sim/trigger_fault) + `rosrun cell_nodes alarms_node`. The robot driver's state and the wrist wrench come from this
test's own publishers (no controller connection needed for them); the device fault comes from the real sim."""
from __future__ import annotations

import os
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path
from typing import Iterator

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node, service_up as _service_up
from sim.tests.conftest import SimProcess, sim_env

HOST = "127.0.0.61"
ROOT = Path(__file__).resolve().parents[4]
WRENCH = "/alarms_test/wrench"


class Latest:
    """Keeps the newest message of a topic."""

    def __init__(self, topic: str, mtype) -> None:
        self.msg = None
        self.count = 0
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=50)

    def _cb(self, msg) -> None:
        self.msg = msg
        self.count += 1


class Driver:
    """Stands in for the robot driver: publishes cell_msgs/RobotState at 10 Hz until stopped."""

    def __init__(self) -> None:
        from cell_msgs.msg import RobotState
        self.pub = rospy.Publisher("/cell/manual/arm/state", RobotState, queue_size=5)
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


@pytest.fixture(scope="module")
def cell(roscore: str, tmp_path_factory) -> Iterator[dict]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["alarms"] = {"force_limit_n": 80, "wrench_topics": [WRENCH], "fault_topics": ["/sim/faults"], "timeout_s": 1}
    path = tmp_path_factory.mktemp("alarms") / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    # The sim for its device faults only: no cameras, no sensor topics (a cell file without devices).
    sim = SimProcess(HOST, ["--no-cameras", "--cell", str(ROOT / "sim/tests/cells/no-devices.yaml")], sim_env(roscore))
    nodes = Nodes()
    nodes.run("operation_mode", "operation_mode_node", f"_cell_config:={path}", "__name:=operation_mode_alarms_test")
    node = nodes.run("alarms", "alarms_node", f"_cell_config:={path}", "__name:=alarms_test")
    driver = None
    try:
        client_node("alarms_test_client")
        sim.wait_ready()
        nodes.wait_ready("/cell/alarms/reset", "/cell/set_mode", "/sim/trigger_fault", what="the nodes' services")
        driver = Driver()
        yield {"path": path, "driver": driver, "log": str(node.log_path)}
    finally:
        if driver:
            driver.stop()
        nodes.stop()
        took = sim.stop()
        nodes.check()
        assert "Traceback" not in sim.output(), sim.output()[-3000:]
        assert took < 5


def active(rec: Latest) -> dict[str, bool]:
    return {a.id: a.active for a in rec.msg.alarms} if rec.msg else {}


def test_faults_become_alarms_switch_the_mode_and_reset_clears_them(cell) -> None:
    from cell_msgs.msg import AlarmList, OperationMode, SafetyStatus
    from cell_msgs.srv import SetMode, TriggerFault
    from geometry_msgs.msg import WrenchStamped
    from std_srvs.srv import Trigger

    alarms = Latest("/cell/alarms/list", AlarmList)
    status = Latest("/cell/alarms/status", SafetyStatus)
    mode = Latest("/cell/mode", OperationMode)
    trigger = rospy.ServiceProxy("/sim/trigger_fault", TriggerFault)
    reset = rospy.ServiceProxy("/cell/alarms/reset", Trigger)
    wait_for(lambda: status.msg and status.msg.controller_connected and mode.msg, 10, what="status with the driver")
    assert (status.msg.status, status.msg.safety_mode, status.msg.robot_mode) == ("normal", "NORMAL", "RUNNING")
    assert alarms.msg.alarms == [] and status.msg.highest_severity == -1
    assert rospy.ServiceProxy("/cell/set_mode", SetMode)(mode="running", source="test").success
    wait_for(lambda: mode.msg.mode == "running", 5, what="mode running")

    # A device fault through the real sim: an active error alarm, and the operation mode goes to alarm.
    t0 = time.time()
    assert trigger("gripper_fault").success
    wait_for(lambda: active(alarms) == {"device.gripper_fault": True}, 5, what="gripper fault alarm")
    (a,) = alarms.msg.alarms
    assert (a.severity, a.source, a.count) == (2, "device", 1) and "Gripper fault" in a.text
    assert t0 - 1 < a.since.to_sec() <= a.last_seen.to_sec()
    wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("alarm", "alarms"), 5, what="mode alarm")
    wait_for(lambda: status.msg.status == "fault" and status.msg.active_count == 1, 3, what="status fault")
    assert status.msg.text == a.text and status.msg.highest_severity == 2

    # Cleared at the device: inactive (still listed), and the mode goes back to what it was.
    assert trigger("reset").success
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

    # A late subscriber (another process) gets the current list at once: latched.
    out = subprocess.run(["rostopic", "echo", "-n", "1", "/cell/alarms/list"], capture_output=True, text=True,
                         timeout=20)
    late = yaml.safe_load(out.stdout.split("---")[0])
    assert [(x["id"], x["active"]) for x in late["alarms"]] == [("robot.arm.protective_stop", True)]

    cell["driver"].msg.safety_mode = "NORMAL"
    wait_for(lambda: active(alarms) == {"robot.arm.protective_stop": False}, 3, what="protective stop gone")
    wait_for(lambda: (mode.msg.mode, mode.msg.source) == ("running", "alarms"), 5, what="mode back again")

    # The wrist force above the limit (norm 85 N, no single axis above 80 N).
    wrench = rospy.Publisher(WRENCH, WrenchStamped, queue_size=5)
    wait_for(lambda: wrench.get_num_connections() > 0, 5, what="the node subscribed to the wrench")
    msg = WrenchStamped()
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = 60.0, 60.0, -5.0
    wrench.publish(msg)
    wait_for(lambda: active(alarms).get("force.limit") is True, 3, what="force limit alarm")
    msg.wrench.force.x, msg.wrench.force.y = 10.0, 0.0
    wrench.publish(msg)
    wait_for(lambda: active(alarms).get("force.limit") is False, 3, what="force back under the limit")
    assert reset().message.startswith("cleared 2 inactive alarms")

    # A module that became incomplete (the modules node's message, when this checkout has it built).
    try:
        from cell_msgs.msg import ModuleState, ModuleStates
    except ImportError:
        ModuleState = ModuleStates = None
    if ModuleStates is not None:
        modules = rospy.Publisher("/cell/modules/state", ModuleStates, queue_size=5, latch=True)
        modules.publish(ModuleStates(modules=[ModuleState(name="vision", state="incomplete", nodes=["/cam", "/det"],
                                                          alive=[True, False], message="not running: /det")]))
        wait_for(lambda: active(alarms).get("module.vision") is True, 5, what="incomplete module alarm")
        assert [a.text for a in alarms.msg.alarms if a.id == "module.vision"] == \
            ["module vision is incomplete: not running: /det"]
        assert mode.msg.mode == "running"                      # a warning does not switch the mode
        modules.publish(ModuleStates(modules=[ModuleState(name="vision", state="active")]))
        wait_for(lambda: active(alarms).get("module.vision") is False, 3, what="module complete again")
        modules.unregister()

    # The driver falls silent (timeout_s 1): an error alarm, the controller counts as not connected.
    cell["driver"].stop()
    wait_for(lambda: active(alarms).get("robot.arm.no_state") is True, 4, what="no robot state alarm")
    wait_for(lambda: not status.msg.controller_connected and status.msg.status == "fault", 3, what="status")
    assert (status.msg.safety_mode, status.msg.robot_mode) == ("", "")
    wait_for(lambda: mode.msg.mode == "alarm", 5, what="mode alarm for the silent driver")
    # The wrench stopped too: its warning is there.
    assert active(alarms).get("force.no_data") is True
    for rec in (alarms, status, mode):
        rec.sub.unregister()
