"""The routines node end to end: roscore + the simulated controller + the robot driver (`rosrun cell_nodes
manual_node`) + `rosrun cell_nodes routines_node`, used over ROS the way the BFF relays the page's calls: move the
arm, record two poses and a gripper action, save, run from elsewhere (the arm reaches both poses within 1 mm, the
gripper closes), the log; stop during a run stops the arm; rename, delete, refusals."""
from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import threading
import time
from pathlib import Path
from typing import Iterator

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node, start_sim

HOST = "127.0.0.71"
DEMO = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"


class Recorder:
    """Every message of a topic, with when it arrived."""

    def __init__(self, topic: str, mtype) -> None:
        self.msgs: list[tuple[float, object]] = []
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=500)

    def _cb(self, msg) -> None:
        with self._lock:
            self.msgs.append((time.monotonic(), msg))

    @property
    def msg(self):
        with self._lock:
            return self.msgs[-1][1] if self.msgs else None

    def since(self, t0: float) -> list:
        with self._lock:
            return [m for t, m in self.msgs if t >= t0]


class Cell:
    def __init__(self, data_dir: Path, routines: subprocess.Popen) -> None:
        self.data_dir = data_dir
        self.routines = routines


@pytest.fixture(scope="module")
def cell(roscore: str, tmp_path_factory) -> Iterator[Cell]:
    """The cell file is the demo's with routines at the driver's top TCP speed (a shorter test)."""
    data_dir = tmp_path_factory.mktemp("routines-data")
    cell = yaml.safe_load(DEMO.read_text())
    cell["routines"]["speed"] = 0.25
    cell_file = data_dir / "cell.yaml"
    cell_file.write_text(yaml.safe_dump(cell))
    sim = start_sim(HOST, "--no-ros", "--no-cameras")
    node_env = dict(os.environ, DATA_DIR=str(data_dir))
    node_env.pop("CELL_CONFIG", None)
    nodes = Nodes()
    nodes.run("manual", "manual_node", f"_cell_config:={cell_file}", f"_ur_host:={HOST}",
              "__name:=manual_routines_test", env=node_env)
    routines = nodes.run("routines", "routines_node", f"_cell_config:={cell_file}", "__name:=routines_test",
                         env=node_env)
    try:
        client_node("routines_test_client")
        nodes.wait_ready("/cell/manual/stop", "/cell/routines/stop")
        yield Cell(data_dir, routines.proc)
    finally:
        nodes.stop()
        sim.stop()
        nodes.check()
        assert routines.took < 5, f"the routines node took {routines.took:.1f} s to stop"


def speed(state) -> float:
    return math.dist(state.tcp_speed[:3], [0, 0, 0])


def dist(a, b) -> float:
    return math.dist(list(a)[:3], list(b)[:3])


def test_record_save_run_stop_through_ros(cell: Cell) -> None:
    import rtde_receive
    from cell_msgs.msg import LogEntries, RobotState, RoutineRunState, RoutineStep
    from cell_msgs.srv import (DeleteRoutine, GetPose, ListRoutines, MoveNamed, MoveRelative, RecordStep,
                               RenameRoutine, RunRoutine, SaveRoutine, ToolAction)
    from std_srvs.srv import Trigger

    data_dir = cell.data_dir
    t_start = time.monotonic()
    robot = Recorder("/cell/manual/arm/state", RobotState)
    run_state = Recorder("/cell/routines/state", RoutineRunState)
    log = Recorder("/cell/routines/log", LogEntries)
    wait_for(lambda: robot.msg is not None and robot.msg.connected, 15, what="the driver connected")
    wait_for(lambda: run_state.msg is not None, 5, what="the latched run state")
    assert (run_state.msg.state, run_state.msg.step, run_state.msg.name) == ("idle", 0, "")
    watch = rtde_receive.RTDEReceiveInterface(HOST)
    gripper_closed = lambda: bool(watch.getActualDigitalInputBits() & 2)  # noqa: E731 (DI1: "closed")

    def call(service: str, srv, **kwargs):
        return rospy.ServiceProxy(service, srv)(**kwargs)

    def ok(r) -> None:
        assert r.success, r.message

    def pose_now() -> list[float]:
        r = call("/cell/manual/get_pose", GetPose, group="arm")
        ok(r)
        return list(r.tcp_pose)

    # Teach: the arm moved by the driver (any way counts), then its pose recorded.
    ok(call("/cell/manual/move_named", MoveNamed, group="arm", name="home", speed=1.0, acceleration=1.5))
    ok(call("/cell/manual/tool", ToolAction, tool="gripper", action="open"))
    assert not gripper_closed()
    move_rel = lambda offset: ok(call("/cell/manual/move_relative", MoveRelative, group="arm",  # noqa: E731
                                      offset=offset, frame="base", speed=0.25, acceleration=1.0))
    move_rel([0.05, 0.0, -0.05, 0, 0, 0])
    r1 = call("/cell/routines/record", RecordStep, group="arm", tool="", kind="pose", action="")
    ok(r1)
    assert r1.step.kind == "pose" and len(r1.step.pose) == 6 and len(r1.step.joints) == 6
    assert dist(r1.step.pose, pose_now()) < 1e-4
    assert r1.message.startswith("Pose recorded: x ") and r1.message.endswith(" rad")
    move_rel([0.0, 0.15, 0.05, 0, 0, 0])
    r2 = call("/cell/routines/record", RecordStep, group="arm", tool="", kind="pose", action="")
    ok(r2)
    assert 0.15 < dist(r1.step.pose, r2.step.pose) < 0.17
    r3 = call("/cell/routines/record", RecordStep, group="", tool="gripper", kind="action", action="close")
    assert (r3.success, r3.message, r3.step.kind, r3.step.tool, r3.step.action) == \
        (True, "Gripper close recorded", "action", "gripper", "close")
    assert not gripper_closed()  # recording an action does not run it
    bad = call("/cell/routines/record", RecordStep, group="legs", tool="", kind="pose", action="")
    assert (bad.success, bad.message) == (False, "unknown motion group 'legs' for routines (routines.groups: arm)")

    # Save (the page's draft: pose 1, close, pose 2), refusals, the file on disk, the list.
    draft = [r1.step, r3.step, r2.step]
    save = lambda name, steps, overwrite=False: call("/cell/routines/save", SaveRoutine, name=name,  # noqa: E731
                                                     group="arm", tool="gripper", steps=steps, overwrite=overwrite)
    r = save("pick two", draft)
    assert (r.success, r.message) == (True, "routine pick two saved (3 steps)")
    assert r.code == "routines.saved" and ("steps.code", "routines.steps") in [(kv.key, kv.value) for kv in r.params]
    r = save("pick two", draft)
    assert (r.success, r.message) == (False, "a routine named 'pick two' exists already")
    r = save("../pick", draft)
    assert (r.success, r.message) == (False, "invalid routine name '../pick': use letters, digits, space, - _ .")
    r = save("short", [RoutineStep(kind="pose", pose=[0.1, 0.2])])
    assert (r.success, r.message) == (False, "step 1: a pose needs 6 finite numbers (x, y, z in m, rx, ry, rz in "
                                             "rad), got 2 values")
    doc = json.loads((data_dir / "routines" / "pick two.json").read_text())
    assert doc["group"] == "arm" and [s["kind"] for s in doc["steps"]] == ["pose", "action", "pose"]
    (data_dir / "routines" / "broken.json").write_text("{not json")
    listed = call("/cell/routines/list", ListRoutines)
    assert listed.success and [x.name for x in listed.routines] == ["broken", "pick two"]
    assert listed.routines[0].error.startswith("broken.json: the file is not valid JSON")
    got = listed.routines[1]
    assert got.error == "" and got.group == "arm" and got.tool == "gripper" and len(got.steps) == 3
    assert list(got.steps[0].pose) == list(r1.step.pose) and got.modified.to_sec() > 0

    # Run it with the arm elsewhere: it reaches pose 1, closes the gripper, reaches pose 2.
    ok(call("/cell/manual/move_named", MoveNamed, group="arm", name="home", speed=1.0, acceleration=1.5))
    assert dist(pose_now(), r1.step.pose) > 0.05
    t0 = time.monotonic()
    r = call("/cell/routines/run", RunRoutine, name="pick two")
    took = time.monotonic() - t0
    assert (r.success, r.message, r.code) == (True, "routine pick two done", "routines.done")
    tcp = [m.tcp_pose for m in robot.since(t0) if len(m.tcp_pose) == 6]
    near1 = min(dist(p, r1.step.pose) for p in tcp)
    final = pose_now()
    print(f"\nrun of 3 steps: {took:.1f} s; closest to pose 1: {near1 * 1000:.2f} mm; pose 2 at the end: "
          f"{dist(final, r2.step.pose) * 1000:.2f} mm")
    assert near1 < 0.001 and dist(final, r2.step.pose) < 0.001
    assert gripper_closed()
    assert "gripper close done" in [m.message for m in robot.since(t0)]
    # The service answers, then the node publishes "idle": the message may still be on its way.
    wait_for(lambda: run_state.msg.state == "idle", 5, what="the run state back to idle")
    states = [(m.state, m.step, m.total) for m in run_state.since(t0)]
    assert states == [("running", 0, 3), ("running", 1, 3), ("running", 2, 3), ("running", 3, 3), ("idle", 0, 3)]
    wait_for(lambda: log.msg.entries[-1].text == "Routine pick two done", 5, what="the log's last entry")
    texts = [e.text for e in log.msg.entries]
    assert [e.code for e in log.msg.entries][2:] == [
        "routines.action_recorded", "routines.saved_log", "routines.started_log", "routines.step_reached",
        "routines.step_done", "routines.step_reached", "routines.done_log"]
    assert texts[:2] == [r1.message, r2.message] and texts[2] == "Gripper close recorded"
    assert texts[3:5] == ["Routine pick two saved (3 steps)", "Routine pick two started (3 steps, group arm)"]
    assert texts[5].startswith("Step 1 of 3 reached: pose x ") and texts[6] == "Step 2 of 3 done: gripper close"
    assert texts[7].startswith("Step 3 of 3 reached: pose x ") and len(texts) == 9

    # Stop during a run: the arm stops, the run answers "stopped".
    ok(call("/cell/manual/tool", ToolAction, tool="gripper", action="open"))
    ok(save("back and forth", [r1.step, r2.step, r1.step, r2.step]))
    answer: list = []
    runner = threading.Thread(target=lambda: answer.append(call("/cell/routines/run", RunRoutine,
                                                                name="back and forth")))
    runner.start()
    # A move from one recorded pose to the other, at cruise speed (a busy CPU may make us see step 3 or 4 first).
    wait_for(lambda: run_state.msg.step >= 2 and robot.msg.motion == "moving"
             and math.dist(robot.msg.tcp_speed[:3], [0, 0, 0]) > 0.2, 15, what="a move between the poses at speed")
    again = call("/cell/routines/run", RunRoutine, name="pick two")
    assert (again.success, again.message) == (False, "routine back and forth is running: stop it first")
    t0 = time.monotonic()
    r = call("/cell/routines/stop", Trigger)
    stop_answer = time.monotonic() - t0
    assert (r.success, r.message) == (True, "routine back and forth stopped")
    wait_for(lambda: math.dist(robot.msg.tcp_speed[:3], [0, 0, 0]) < 0.001 and robot.msg.motion == "idle", 2,
             what="standstill")
    standstill = time.monotonic() - t0
    runner.join(10)
    print(f"stop: answered after {stop_answer * 1000:.0f} ms, standstill seen after {standstill * 1000:.0f} ms")
    assert (answer[0].success, answer[0].message) == (False, "stopped")
    assert stop_answer < 1.5
    here = pose_now()
    assert min(dist(here, r1.step.pose), dist(here, r2.step.pose)) > 0.002  # stopped on the way, not at a target
    wait_for(lambda: (run_state.msg.state, run_state.msg.step, run_state.msg.message) ==
             ("idle", 0, "routine back and forth stopped"), 5, what="the run state: idle after the stop")
    assert (run_state.msg.message_code, [(kv.key, kv.value) for kv in run_state.msg.message_params]) == (
        "routines.stopped", [("name", "back and forth")])
    wait_for(lambda: re.fullmatch(r"Routine back and forth stopped at step [234] of 4", log.msg.entries[-1].text), 5,
             what="the stop in the log")
    assert log.msg.entries[-1].level == "warning"
    assert "Run refused: routine back and forth is running: stop it first" in [e.text for e in log.msg.entries]
    r = call("/cell/routines/stop", Trigger)
    assert (r.success, r.message) == (True, "no routine is running")

    # Rename and delete.
    r = call("/cell/routines/rename", RenameRoutine, name="pick two", new_name="back and forth")
    assert (r.success, r.message) == (False, "a routine named 'back and forth' exists already")
    r = call("/cell/routines/rename", RenameRoutine, name="pick two", new_name="pick 2")
    assert (r.success, r.message) == (True, "routine pick two renamed to pick 2")
    r = call("/cell/routines/delete", DeleteRoutine, name="back and forth")
    assert (r.success, r.message) == (True, "routine back and forth deleted")
    r = call("/cell/routines/delete", DeleteRoutine, name="back and forth")
    assert (r.success, r.message) == (False, "no routine named 'back and forth'")
    assert sorted(os.listdir(data_dir / "routines")) == ["broken.json", "pick 2.json"]
    assert [x.name for x in call("/cell/routines/list", ListRoutines).routines] == ["broken", "pick 2"]
    watch.disconnect()
    for rec in (robot, run_state, log):
        rec.sub.unregister()
    print(f"the test took {time.monotonic() - t_start:.1f} s")


def test_the_node_stops_a_running_routine_when_it_shuts_down(cell: Cell) -> None:
    """Last in this module: it ends the routines node (SIGINT, as roslaunch and npm stop do)."""
    from cell_msgs.msg import RobotState
    from cell_msgs.srv import ListRoutines, MoveNamed, RunRoutine

    robot = Recorder("/cell/manual/arm/state", RobotState)
    r = rospy.ServiceProxy("/cell/manual/move_named", MoveNamed)(group="arm", name="home", speed=1.0, acceleration=1.5)
    assert r.success, r.message  # far from the routine's first pose: a long first move
    assert [x.name for x in rospy.ServiceProxy("/cell/routines/list", ListRoutines)().routines] == ["broken", "pick 2"]
    answer: list = []
    runner = threading.Thread(target=lambda: answer.append(
        rospy.ServiceProxy("/cell/routines/run", RunRoutine)(name="pick 2")))
    runner.start()
    wait_for(lambda: robot.msg is not None and robot.msg.motion == "moving" and speed(robot.msg) > 0.1, 15,
             what="the first move at speed")
    t0 = time.monotonic()
    cell.routines.send_signal(signal.SIGINT)
    wait_for(lambda: robot.msg.motion == "idle" and speed(robot.msg) < 0.001, 5, what="standstill")
    print(f"\nstandstill {(time.monotonic() - t0) * 1000:.0f} ms after SIGINT to the routines node; "
          f"driver: {robot.msg.message}")
    assert robot.msg.message == "stopped"
    cell.routines.wait(10)
    runner.join(10)
    # The run's answer went out before the node ended.
    assert len(answer) == 1 and (answer[0].success, answer[0].message) == (False, "stopped")
    robot.sub.unregister()
