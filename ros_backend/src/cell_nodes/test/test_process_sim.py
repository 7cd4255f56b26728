"""The demo cell's process against the simulated cell: roscore + the sim with ROS (its /sim/objects show where the
cubes are) + the operation-mode node + the robot driver (manual_node) + process_server + process_node, all with
config/demo-cell.yaml, used through /cell/process/* as the page does. A whole pick-and-place cycle (with a pause
and a resume in it) must put cube 1 into pocket 1; a stop must end a run with the arm standing still; a protective
stop must end a run in error with the driver's message."""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any, Iterator

import pytest
import rospy

from conftest import wait_for
from nodes_helpers import Nodes, client_node
from sim.tests.conftest import SimProcess, sim_env
from test_process_node import Latest, Ui, start_process_nodes

HOST = "127.0.0.66"
CELL = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"
# rad/s: the joint speed readings of a held arm jitter up to ~0.013 rad/s; a moving arm here is at 0.05 and more.
STANDSTILL = 0.03
POCKETS = [(-0.35, 0.292), (-0.35, 0.35), (-0.35, 0.408)]   # sim/world.py fixture_slots (FIXTURE_POS -0.35, 0.35)


class Joints:
    """The newest /joint_states (125 Hz: only the latest is kept)."""

    def __init__(self) -> None:
        from sensor_msgs.msg import JointState
        self.msg: Any = None
        self.sub = rospy.Subscriber("/joint_states", JointState, self._cb, queue_size=1)

    def _cb(self, msg: Any) -> None:
        self.msg = msg

    def speed(self) -> float:
        return max(abs(v) for v in self.msg.velocity)

    def position(self) -> list[float]:
        return list(self.msg.position)

    def held_still(self, seconds: float) -> tuple[float, float]:
        """Watch the arm for `seconds`: the largest joint drift (rad) and joint speed (rad/s) seen."""
        q0 = self.position()
        drift = speed = 0.0
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            drift = max(drift, max(abs(a - b) for a, b in zip(self.position(), q0)))
            speed = max(speed, self.speed())
            time.sleep(0.02)
        return drift, speed


@pytest.fixture(scope="module")
def cell(roscore: str) -> Iterator[dict]:
    sim = SimProcess(HOST, ["--no-cameras", "--cell", str(CELL)], sim_env(roscore))
    procs = Nodes()
    ui = joints = objects = None
    try:
        sim.wait_ready()
        client_node("process_test_client")
        from cell_msgs.msg import RobotState
        from geometry_msgs.msg import PoseArray
        procs.run("operation_mode", "operation_mode_node", f"_cell_config:={CELL}", "__name:=process_sim_mode")
        procs.run("manual", "manual_node", f"_cell_config:={CELL}", f"_ur_host:={HOST}", "__name:=process_sim_manual")
        start_process_nodes(procs, CELL, "process_sim")
        ui, joints = Ui(), Joints()
        objects = Latest("/sim/objects", PoseArray)
        robot = Latest("/cell/manual/arm/state", RobotState)
        procs.wait_ready("/cell/process/start", "/cell/manual/stop", what="the nodes' services")
        wait_for(lambda: robot.msg is not None and robot.msg.connected and joints.msg is not None, 15,
                 what="the driver connected to the sim")
        robot.sub.unregister()
        wait_for(lambda: ui.state.msg is not None and ui.state.msg.ready, 10, what="the process client ready")
        wait_for(lambda: objects.msg is not None and len(objects.msg.poses) == 3, 10, what="/sim/objects")
        yield {"ui": ui, "joints": joints, "objects": objects, "start": [(p.position.x, p.position.y, p.position.z)
                                                                        for p in objects.msg.poses]}
    finally:
        for rec in (joints, objects):
            if rec is not None:
                rec.sub.unregister()
        if ui is not None:
            ui.close()
        procs.stop()
        sim.stop()
        procs.check()
        assert "Traceback" not in sim.output(), sim.output()[-3000:]


@pytest.fixture
def env(cell: dict) -> Iterator[dict]:
    yield cell
    if cell["ui"].state.msg.state not in ("idle", "error"):   # a failed test must not leave a run going
        cell["ui"].stop()


def test_a_cycle_puts_the_first_cube_into_the_first_pocket_with_a_pause_in_it(env: dict) -> None:
    ui, joints, objects = env["ui"], env["joints"], env["objects"]
    t0 = time.monotonic()
    s = ui.state.msg
    assert s.at_start and s.start_configuration == "home" and s.cycle == 1   # the sim boots at home
    r = ui.start(cycles=1)
    assert (r.success, r.message) == (True, "started: 1 cycle from cycle 1")
    ui.wait_mode("running")
    # Pause while the gripper closes on the cube: the step finishes, then the arm is held.
    wait_for(lambda: ui.state.msg.step == "Gripper close", 30, what="the gripper closing")
    r = ui.pause()
    assert r.success, r.message
    s = ui.wait_state("paused", 10)
    assert (s.step, s.step_index, s.current) == ("Gripper close", 4, 0)
    ui.wait_mode("paused")
    drift, speed = joints.held_still(0.6)
    print(f"\npaused: joint drift {drift:.5f} rad, speed {speed:.5f} rad/s over 0.6 s")
    # Held: no drift (the joint speed readings show noise of ~0.01 rad/s at standstill, no motion).
    assert drift < 1e-3 and speed < 0.05, f"the arm moved while paused: {drift:.5f} rad, {speed:.5f} rad/s"
    assert objects.msg.poses[0].position.z < 0.03          # the cube is still on the table, in the fingers
    r = ui.resume()
    assert (r.success, r.message) == (True, "resumed")
    # (The part check takes a few ms: the log has it, a look at the state might not.)
    wait_for(lambda: "Resumed: next 'Check the part is in the gripper'" in ui.texts(), 5, what="the next step after the resume")
    s = ui.wait_state("idle", 60)
    took = time.monotonic() - t0
    assert (s.message, s.cycles_done, s.cycle) == ("1 cycle done", 1, 2)
    assert 5 < s.last_cycle_s < took + 1
    assert "Resumed: next 'Check the part is in the gripper'" in ui.texts()
    assert "Lift the part" in ui.texts()                    # the part was there (DI2), the cycle went on
    assert ui.texts().count("Gripper close") == 1          # the paused step was not run again
    ui.wait_mode("idle")
    wait_for(lambda: ui.state.msg.at_start, 3, what="back at home")
    # Where the cube is now (ground truth from the sim), after it settled.
    time.sleep(0.5)  # /sim/objects at 5 Hz: a fresh sample after the release (nothing else to await)
    cube = objects.msg.poses[0].position
    px, py = POCKETS[0]
    print(f"\ncycle with pause: {s.last_cycle_s:.1f} s; cube 1 at ({cube.x:.4f}, {cube.y:.4f}, {cube.z:.4f}); "
          f"pocket 1 at ({px}, {py})")
    assert math.hypot(cube.x - px, cube.y - py) < 0.015, "cube 1 is not in pocket 1"
    assert 0.02 <= cube.z <= 0.03, f"cube 1 is not resting in the pocket (z {cube.z:.4f})"
    for (x0, y0, _), p in zip(env["start"][1:], objects.msg.poses[1:]):
        assert math.hypot(p.position.x - x0, p.position.y - y0) < 0.01, "the other cubes must stay where they were"


def test_stop_ends_the_run_with_the_arm_stopped(env: dict) -> None:
    ui, joints = env["ui"], env["joints"]
    cycle = ui.state.msg.cycle                   # 2 after the first test's cycle
    part = f"part {(cycle - 1) % 3 + 1}"
    r = ui.start(cycles=0)
    assert (r.success, r.message) == (True, f"started: until stopped from cycle {cycle}")
    wait_for(lambda: ui.state.msg.step == f"Move to {part} (approach)" and joints.speed() > 0.05, 30,
             what=f"the arm moving to {part}")
    t0 = time.monotonic()
    r = ui.stop()
    took = time.monotonic() - t0
    assert (r.success, r.message) == (True, "stopped by the operator")
    print(f"\nstop answered after {took:.2f} s, arm speed then {joints.speed():.4f} rad/s")
    assert took < 2.5
    s = ui.wait_state("idle", 2)
    assert s.state == "idle" and s.cycle == cycle and s.cycles_done == 0    # the interrupted cycle comes again
    wait_for(lambda: joints.speed() < STANDSTILL, 0.5, what="standstill")
    drift, speed = joints.held_still(0.5)
    print(f"after the stop: joint drift {drift:.5f} rad, speed {speed:.5f} rad/s over 0.5 s")
    assert drift < 1e-3 and speed < 0.05, f"the arm moved after the stop: {drift:.5f} rad, {speed:.5f} rad/s"
    ui.wait_mode("idle")
    assert "Stop: stopped by the operator" in ui.texts()


def test_a_protective_stop_ends_the_run_in_error_with_the_drivers_message(env: dict) -> None:
    from cell_msgs.srv import TriggerFault
    ui, joints = env["ui"], env["joints"]
    trigger = rospy.ServiceProxy("/sim/trigger_fault", TriggerFault)
    assert ui.start(cycles=1).success
    wait_for(lambda: ui.state.msg.step.startswith("Move to") and joints.speed() > 0.05, 30, what="a move running")
    try:
        assert trigger("protective_stop").success
        s = ui.wait_state("error", 10)
        assert "protective stop" in s.message and s.message.startswith(s.step + " failed: "), (s.message, ui.texts())
        wait_for(lambda: joints.speed() < STANDSTILL, 2, what="standstill")
        wait_for(lambda: any(t.startswith("Error: ") and "protective stop" in t for t in ui.texts()), 3,
                 what="the error in the log")
        ui.wait_mode("idle")                  # no alarms node here: nothing holds the mode at alarm
        errors = sum(t.startswith("Error: ") for t in ui.texts())
        r = ui.start(cycles=1)                # refused by the driver, not by the process: it reports why
        assert r.success, r.message
        wait_for(lambda: sum(t.startswith("Error: ") for t in ui.texts()) > errors, 10, what="the next run's error")
        s = ui.wait_state("error", 2)
        assert s.message == "Move to home failed: protective stop is active: clear it first", (s.message, ui.texts())
    finally:
        trigger("reset")
