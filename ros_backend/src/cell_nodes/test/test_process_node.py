"""The process nodes end to end over ROS, with stand-ins for the robot driver and the routines node (this test's own
rospy services, so every call and its timing is under the test's control): roscore + the operation-mode node +
`rosrun cell_nodes process_server` + `rosrun cell_nodes process_node`, used the way the page does through the BFF
(/cell/process/* services and topics). The real robot motion is test_process_sim.py's."""
from __future__ import annotations

import os
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, Iterator, Optional

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node, service_up

ROOT = Path(__file__).resolve().parents[4]
HOME = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]
READY_TOPIC = "/process_test/ready"


class Latest:
    """Keeps the newest message of a topic, and every message."""

    def __init__(self, topic: str, mtype: Any) -> None:
        self.msg: Any = None
        self.msgs: list[Any] = []
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=200)

    def _cb(self, msg: Any) -> None:
        with self._lock:
            self.msg = msg
            self.msgs.append(msg)

    def seen(self, pred) -> bool:
        with self._lock:
            return any(pred(m) for m in self.msgs)


def start_process_nodes(procs: Nodes, cell: Path, tag: str) -> None:
    procs.run("process_server", "process_server", f"_cell_config:={cell}", f"__name:={tag}_server")
    procs.run("process_node", "process_node", f"_cell_config:={cell}", f"__name:={tag}_client")


class StandInDriver:
    """/cell/manual/{move_named, move_relative, move_pose, tool, stop} and /cell/routines/{run, stop}: each call is
    recorded and takes `delay` s; a kind in `block` waits until stopped or released; a kind in `fail` fails."""

    def __init__(self) -> None:
        from cell_msgs.srv import MoveNamed, MovePose, MoveRelative, RunRoutine, ToolAction
        from std_srvs.srv import Trigger
        self.calls: list[tuple] = []
        self.stops = 0
        self.routine_stops = 0
        self.delay = 0.05
        self.block: set[str] = set()
        self.fail: dict[str, str] = {}
        self.blocked = threading.Event()
        self.release = threading.Event()
        self._stopped = threading.Event()
        self._lock = threading.Lock()
        ns = "/cell/manual"
        self.services = [
            rospy.Service(f"{ns}/move_named", MoveNamed, lambda r: self._do("move_named", r.group, r.name, r.speed,
                                                                           r.acceleration)),
            rospy.Service(f"{ns}/move_relative", MoveRelative, lambda r: self._do("move_relative", r.group,
                                                                                 list(r.offset), r.frame)),
            rospy.Service(f"{ns}/move_pose", MovePose, lambda r: self._do("move_pose", r.group, list(r.pose))),
            rospy.Service(f"{ns}/tool", ToolAction, lambda r: self._do("tool", r.tool, r.action)),
            rospy.Service(f"{ns}/stop", Trigger, self._stop),
            rospy.Service("/cell/routines/run", RunRoutine, lambda r: self._do("routine", r.name)),
            rospy.Service("/cell/routines/stop", Trigger, self._stop_routine),
        ]

    def kinds(self) -> list[str]:
        with self._lock:
            return [c[0] for c in self.calls]

    def _do(self, kind: str, *args: Any) -> dict[str, Any]:
        """The fake's answer as fields: the move services' responses also carry a code, left empty here."""
        ok, message = self._answer(kind, *args)
        return {"success": ok, "message": message}

    def _answer(self, kind: str, *args: Any) -> tuple[bool, str]:
        with self._lock:
            self.calls.append((kind, *args))
            self._stopped.clear()
        if kind in self.block:
            self.blocked.set()
            while not (self._stopped.is_set() or self.release.is_set()):
                time.sleep(0.005)
            self.blocked.clear()
            if self._stopped.is_set():
                return False, "stopped"
        elif self._stopped.wait(self.delay):
            return False, "stopped"
        if kind in self.fail:
            return False, self.fail[kind]
        return True, f"{kind} done"

    def _stop(self, _req: Any) -> tuple[bool, str]:
        with self._lock:
            self.stops += 1
        self._stopped.set()
        return True, "stopped"

    def _stop_routine(self, _req: Any) -> tuple[bool, str]:
        with self._lock:
            self.routine_stops += 1
        self._stopped.set()
        return True, "stopping"

    def reset(self) -> None:
        with self._lock:
            self.calls.clear()
            self.stops = self.routine_stops = 0
        self.block.clear()
        self.fail.clear()
        self.release.clear()

    def shutdown(self) -> None:
        for s in self.services:
            s.shutdown("test done")


class Ui:
    """The page's side: the process services, its state and log, the operation mode."""

    def __init__(self) -> None:
        from cell_msgs.msg import LogEntries, OperationMode, ProcessState
        from cell_msgs.srv import ProcessStart, ProcessStep, SetMode
        from std_srvs.srv import SetBool, Trigger
        ns = "/cell/process"
        self.start = rospy.ServiceProxy(f"{ns}/start", ProcessStart)
        self.step = rospy.ServiceProxy(f"{ns}/step", ProcessStep)
        self.stop = rospy.ServiceProxy(f"{ns}/stop", Trigger)
        self.pause = rospy.ServiceProxy(f"{ns}/pause", Trigger)
        self.resume = rospy.ServiceProxy(f"{ns}/resume", Trigger)
        self.set_dry_run = rospy.ServiceProxy(f"{ns}/set_dry_run", SetBool)
        self.set_mode = rospy.ServiceProxy("/cell/set_mode", SetMode)
        self.state = Latest(f"{ns}/state", ProcessState)
        self.log = Latest(f"{ns}/log", LogEntries)
        self.mode = Latest("/cell/mode", OperationMode)

    def texts(self) -> list[str]:
        return [e.text for e in self.log.msg.entries] if self.log.msg else []

    def wait_state(self, state: str, timeout: float = 10, what: Optional[str] = None) -> Any:
        wait_for(lambda: self.state.msg is not None and self.state.msg.state == state, timeout,
                 what=what or f"process state {state} (now {self.state.msg.state if self.state.msg else None}: "
                                f"{self.state.msg.message if self.state.msg else ''})")
        return self.state.msg

    def wait_mode(self, mode: str, timeout: float = 5) -> None:
        wait_for(lambda: self.mode.msg is not None and self.mode.msg.mode == mode, timeout,
                 what=f"operation mode {mode} (now {self.mode.msg.mode if self.mode.msg else None})")

    def close(self) -> None:
        for rec in (self.state, self.log, self.mode):
            rec.sub.unregister()


@pytest.fixture(scope="module")
def cell(roscore: str) -> Iterator[dict]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["process"]["operations"].append({"name": "check", "steps": [
        {"wait_topic": READY_TOPIC, "field": "data", "equals": True, "timeout_s": 10}, {"routine": "demo_routine"}]})
    path = Path(tempfile.mkdtemp(prefix="process-node-")) / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    client_node("process_test_client")
    from std_msgs.msg import Bool
    driver = StandInDriver()
    # The "check" operation's condition: true (latched) unless a test says otherwise, so whole cycles pass it.
    ready = rospy.Publisher(READY_TOPIC, Bool, queue_size=5, latch=True)
    ready.publish(Bool(True))
    procs = Nodes()
    procs.run("operation_mode", "operation_mode_node", f"_cell_config:={path}", "__name:=process_test_mode")
    start_process_nodes(procs, path, "process_test")
    ui = Ui()
    try:
        procs.wait_ready("/cell/process/start", "/cell/set_mode", what="the process nodes' services")
        ui.wait_state("idle", 10)
        wait_for(lambda: ui.state.msg.ready, 10, what="the client seeing the action server")
        yield {"driver": driver, "ui": ui, "procs": procs, "ready": ready}
    finally:
        ui.close()
        ready.unregister()
        driver.shutdown()   # the stand-in services must not outlive this module (the sim test has a real driver)
        procs.stop()
        procs.check(within=5)


@pytest.fixture
def env(cell: dict) -> Iterator[dict]:
    cell["driver"].reset()
    yield cell
    ui = cell["ui"]
    if ui.state.msg.state not in ("idle", "error"):
        ui.stop()
    ui.set_mode(mode="idle", source="test")


def part_number(ui: Ui) -> int:
    """The part-table entry the next run uses (3 parts in the demo cell)."""
    return (ui.state.msg.cycle - 1) % 3 + 1


def test_state_describes_the_process_and_at_start_follows_the_robot(env: dict) -> None:
    from cell_msgs.msg import RobotState
    ui = env["ui"]
    s = ui.state.msg
    assert list(s.operations) == ["pick part", "place in fixture", "return home", "check"]
    assert (s.state, s.ready, s.current, s.step_index, s.dry_run, s.run_mode) == ("idle", True, -1, -1, False, "")
    assert (s.cycle, s.cycles_done, s.start_configuration) == (1, 0, "home")
    assert not s.at_start                               # no robot state yet
    pub = rospy.Publisher("/cell/manual/arm/state", RobotState, queue_size=5)
    try:
        wait_for(lambda: pub.get_num_connections() > 0, 5, what="the client subscribed to the robot state")
        for joints, expected in ((HOME, True), ([0.3] + HOME[1:], False), ([0.004] + HOME[1:], True)):
            pub.publish(RobotState(joint_positions=joints))
            wait_for(lambda: ui.state.msg.at_start == expected, 3, what=f"at_start {expected}")
    finally:
        pub.unregister()
    assert ui.log.msg is not None   # the log topic is latched (maybe empty before the first entry)


def test_dry_run_walks_the_steps_without_calling_the_robot(env: dict) -> None:
    ui, driver = env["ui"], env["driver"]
    r = ui.set_dry_run(True)
    assert r.success and ui.state is not None
    wait_for(lambda: ui.state.msg.dry_run, 3, what="dry_run in the state")
    r = ui.start(cycles=1)
    assert (r.success, r.message) == (True, "started: 1 cycle from cycle 1 (dry run)")
    s = ui.wait_state("running", 3)
    assert s.run_mode == "cycle" and s.cycles_target == 1
    ui.wait_mode("running")
    r = ui.set_dry_run(False)
    assert (r.success, r.message) == (False, "the process is running: change the dry run once it is stopped")
    r = ui.start(cycles=1)
    assert (r.success, r.message) == (False, "the process is already running: stop it first")
    s = ui.wait_state("idle", 15)
    assert (s.message, s.cycles_done, s.cycle, s.cycle_time_s) == ("1 cycle done", 1, 2, 0.0)
    assert s.last_cycle_s > 13 * 0.3 * 0.9                 # 13 steps of dry_run_step_s
    assert driver.calls == [] and driver.stops == 0
    wait_for(lambda: "Done: 1 cycle done" in ui.texts(), 3, what="the end in the log")
    texts = ui.texts()
    assert "Dry run: Move to home" in texts and "Dry run: Move to part 1 (approach)" in texts
    assert "Dry run: Wait for /process_test/ready data = true" in texts and "Cycle 1 done in" in " ".join(texts)
    assert texts.index("Dry run: Move to home") < texts.index("Dry run: Gripper open")
    ui.wait_mode("idle")
    assert ui.set_dry_run(False).success


def test_a_step_runs_one_operation_through_the_driver(env: dict) -> None:
    ui, driver = env["ui"], env["driver"]
    r = ui.step(index=9)
    assert (r.success, r.message) == (False, "no operation 9 (the process has 4: 0 pick part, 1 place in fixture, "
                                             "2 return home, 3 check)")
    r = ui.step(index=2)
    assert (r.success, r.message) == (True, "started: return home once")
    s = ui.wait_state("idle", 5)
    assert s.message == "operation 'return home' done"
    assert driver.calls == [("move_named", "arm", "home", 1.0, 1.5)]      # the section's joint speed/acceleration
    assert ui.state.seen(lambda m: m.run_mode == "step" and m.current == 2 and m.step == "Move to home")


def test_wait_topic_and_routine_steps(env: dict) -> None:
    from std_msgs.msg import Bool
    ui, driver, pub = env["ui"], env["driver"], env["ready"]
    pub.publish(Bool(False))
    try:
        assert ui.step(index=3).success
        wait_for(lambda: ui.state.msg.step == "Wait for /process_test/ready data = true", 5, what="the wait step")
        wait_for(lambda: pub.get_num_connections() > 0, 5, what="the server subscribed to the topic")
        time.sleep(0.3)  # the latched false must not end the wait (nothing to await: the wait has to go on)
        assert ui.state.msg.state == "running" and driver.calls == []
        pub.publish(Bool(True))
        s = ui.wait_state("idle", 5)
        assert s.message == "operation 'check' done"
        assert driver.calls == [("routine", "demo_routine")]
        wait_for(lambda: pub.get_num_connections() == 0, 5, what="the server unsubscribed after the step")
    finally:
        pub.publish(Bool(True))


def test_pause_holds_between_steps_and_resume_goes_on_with_the_next(env: dict) -> None:
    ui, driver = env["ui"], env["driver"]
    driver.block.add("tool")                  # "Gripper open" (step 2) runs until released
    part = f"part {part_number(ui)}"
    assert ui.start(cycles=1).success
    wait_for(driver.blocked.is_set, 5, what="the tool step running")
    r = ui.pause()
    assert (r.success, r.message) == (True, "pausing after the current step")
    s = ui.wait_state("pausing", 3)
    assert s.step == "Gripper open"
    driver.block.clear()
    driver.release.set()
    s = ui.wait_state("paused", 5)
    ui.wait_mode("paused")
    n = len(driver.calls)
    time.sleep(0.5)  # nothing may be called while paused: a time window, nothing to await
    assert len(driver.calls) == n == 2
    assert ui.pause().message == "already paused"
    r = ui.resume()
    assert (r.success, r.message) == (True, "resumed")
    ui.wait_state("idle", 10)
    assert driver.kinds()[:3] == ["move_named", "tool", "move_pose"]      # "Gripper open" was not run again
    texts = ui.texts()
    assert f"Paused after 'Gripper open'; next: 'Move to {part} (approach)'" in texts
    assert f"Resumed: next 'Move to {part} (approach)'" in texts
    # Lines from the server (paused, resumed) and the state's step and message keep their codes and parameters
    # over both hops (server -> client node -> page).
    entries = {e.text: e for e in ui.log.msg.entries}
    paused = entries[f"Paused after 'Gripper open'; next: 'Move to {part} (approach)'"]
    assert paused.code == "process.paused_after"
    assert {(kv.key, kv.value) for kv in paused.params} >= {("after", "Gripper open"), ("after.code", "process.step_tool"),
                                                           ("next.code", "process.step_move_table"), ("next.table", "part")}
    assert ui.resume().message == "the process is not running"


def test_stop_mid_step_and_a_failing_step(env: dict) -> None:
    ui, driver = env["ui"], env["driver"]
    assert ui.stop().message == "the process is not running"
    driver.block.add("move_pose")
    cycle, part = ui.state.msg.cycle, f"part {part_number(ui)}"
    assert ui.start(cycles=0).success
    wait_for(driver.blocked.is_set, 5, what="the approach move running")
    t0 = time.monotonic()
    r = ui.stop()
    took = time.monotonic() - t0
    assert (r.success, r.message) == (True, "stopped by the operator")
    assert took < 3 and driver.stops >= 1
    s = ui.wait_state("idle", 2)
    assert s.current == -1 and s.cycle == cycle         # the cycle was interrupted: it is run again next
    ui.wait_mode("idle")
    assert f"Stopped during 'Move to {part} (approach)': stopped by the operator" in ui.texts()
    assert (s.message, s.message_code) == ("stopped by the operator", "process.reason_operator")

    driver.reset()
    driver.fail["move_pose"] = "pose unreachable: no inverse kinematics solution"
    assert ui.start(cycles=1).success
    s = ui.wait_state("error", 5)
    message = f"Move to {part} (approach) failed: pose unreachable: no inverse kinematics solution"
    assert (s.message, s.current, s.step_index, s.step) == (message, 0, 2, f"Move to {part} (approach)")
    assert (s.message_code, s.step_code) == ("process.step_failed", "process.step_move_table")
    assert driver.stops == 1 and driver.kinds() == ["move_named", "tool", "move_pose"]
    wait_for(lambda: f"Error: {message}" in ui.texts(), 3, what="the error in the log")
    ui.wait_mode("idle")


def test_the_operation_mode_alarm_refuses_start_and_ends_a_run(env: dict) -> None:
    ui, driver = env["ui"], env["driver"]
    assert ui.set_mode(mode="alarm", source="alarms").success
    ui.wait_mode("alarm")

    def refused() -> bool:
        answer = ui.start(cycles=1)
        if answer.success:  # the process node had not had the mode message yet (CI saw it): end that run, ask again
            ui.stop()  # (or the node ends it itself, with an error, when the mode message comes)
            wait_for(lambda: ui.state.msg.state in ("idle", "error"), 5, what="that run ended")
            return False
        return answer.message == "the cell is in alarm: reset it first"
    wait_for(refused, 5, what="start refused in alarm")
    assert ui.set_mode(mode="idle", source="alarms").success
    ui.wait_mode("idle")
    driver.block.add("move_named")
    wait_for(lambda: ui.start(cycles=1).success, 3, what="start accepted once the alarm is gone")
    wait_for(driver.blocked.is_set, 5, what="the first move running")
    ui.wait_mode("running")
    assert ui.set_mode(mode="alarm", source="alarms").success   # what the alarms node does on an error alarm
    # (Not any error state: an earlier run's may still be the last message.)
    wait_for(lambda: ui.state.msg.state == "error"
             and ui.state.msg.message == "the cell went into alarm (alarms): the run was stopped", 5,
             what="the run ended by the alarm")
    assert driver.stops >= 1
    time.sleep(0.3)  # the process must leave the alarm mode alone: a window, nothing to await
    assert ui.mode.msg.mode == "alarm"
    # The alarm clears: the alarms node gives `running` back; the process is idle, so the mode becomes idle.
    assert ui.set_mode(mode="running", source="alarms").success
    ui.wait_mode("idle")
    assert ui.mode.msg.source == "process"
