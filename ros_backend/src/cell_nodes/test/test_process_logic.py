"""The process feature's logic without ROS: the cell file section, step texts and pose tables, the executor with a
fake robot and a fake clock (sequencing, cycling, pause, resume, stop, single operation, dry run, errors, wait on a
topic, routines), the operation-mode rules and the client's state, refusals and cycle counter."""
from __future__ import annotations

import json
import math
import re
import threading
import time
from pathlib import Path
from typing import Any, Callable, Optional

import pytest
import yaml

from cell_nodes.process.client import LOG_SIZE, ProcessClient, memory_problem
from cell_nodes.process.conditions import ConditionError, field_value, holds
from cell_nodes.process.config import ConfigError, MovePose, Tool, parse_cell_process, parse_process
from cell_nodes.process.executor import (ERROR, IDLE, PAUSED, PAUSING, RUNNING, STOPPING, Executor, Progress,
                                         RunRequest, RunResult)
from cell_nodes.process.mode import ModeFollower, alarm_reason
from cell_nodes.said import Said, coded, say
from cell_nodes.process.steps import describe, resolve_pose, table_index

from conftest import wait_for
from said_check import check_said

ROOT = Path(__file__).resolve().parents[4]
MANUAL = {
    "groups": [{"name": "arm", "joints": ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                         "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"],
                "configurations": {"home": [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0],
                                   "pick_approach": [0.4, -1.2, 1.6, -1.97, -1.5708, 0.4]}}],
    "tools": [{"name": "gripper", "actions": [{"name": "open", "steps": [{"wait_s": 0.1}]},
                                              {"name": "close", "steps": [{"wait_s": 0.1}]}]}],
}
SECTION = yaml.safe_load("""
action: /cell/process/run
start_configuration: home
tcp_speed: 0.2
dry_run_step_s: 0.1
poses:
  part:
    - [-0.44, -0.26, 0.032, 3.1416, 0, 0]
    - [-0.48, -0.12, 0.032, 3.1416, 0, 0]
    - [-0.44, 0.00, 0.032, 3.1416, 0, 0]
  pocket:
    - [-0.35, 0.292, 0.042, 3.1416, 0, 0]
    - [-0.35, 0.350, 0.042, 3.1416, 0, 0]
operations:
  - name: pick part
    steps:
      - { move_named: home, speed: 1.0 }
      - { tool: gripper, action: open }
      - { move_pose: part, offset: [0, 0, 0.1, 0, 0, 0], note: approach }
      - { move_pose: part, speed: 0.1 }
      - { tool: gripper, action: close }
      - { move_relative: [0, 0, 0.1, 0, 0, 0] }
  - name: place in fixture
    steps:
      - { move_pose: pocket, offset: [0, 0, 0.1, 0, 0, 0], note: approach }
      - { move_pose: pocket }
      - { tool: gripper, action: open }
      - { wait_s: 0.5 }
  - name: return home
    steps:
      - { move_named: home }
""")


def config(section: Optional[dict] = None, manual: Optional[dict] = MANUAL):
    return parse_process(section or SECTION, manual)


# ================================================================================================ fakes
class FakeClock:
    """Fake time: sleep advances it at once (and yields a little so other threads run)."""

    def __init__(self) -> None:
        self.t = 1000.0
        self._lock = threading.Lock()

    def now(self) -> float:
        with self._lock:
            return self.t

    def sleep(self, seconds: float) -> None:
        with self._lock:
            self.t += seconds
        time.sleep(0.0005)


class FakeRobot:
    """Records calls; every call takes `step_s` of fake time. `gate(kind)`: calls of that kind block until released or
    until a stop; `fail(kind, message)`: they fail."""

    def __init__(self, clock: FakeClock, step_s: float = 1.0) -> None:
        self.clock = clock
        self.step_s = step_s
        self.calls: list[tuple] = []
        self.stops = 0
        self.routine_stops = 0
        self.failures: dict[str, str] = {}
        self.gates: dict[str, threading.Event] = {}
        self.blocked = threading.Event()        # a gated call is waiting
        self.stop_releases = True               # a stop ends a gated call (False: it "arrives after the stop")
        self.stop_s = 0.0                       # how long the stop call takes (real time)
        self.stop_returned = 0.0
        self._stopped = threading.Event()
        self._lock = threading.Lock()

    def gate(self, kind: str) -> threading.Event:
        self.gates[kind] = threading.Event()
        return self.gates[kind]

    def fail(self, kind: str, message: str) -> None:
        self.failures[kind] = message

    def kinds(self) -> list[str]:
        with self._lock:
            return [c[0] for c in self.calls]

    def _do(self, kind: str, *args: Any) -> tuple[bool, str]:
        with self._lock:
            self.calls.append((kind, *args))
        gate = self.gates.get(kind)
        if gate is not None:
            self._stopped.clear()
            self.blocked.set()
            while not gate.is_set():
                if self._stopped.is_set():
                    self.blocked.clear()
                    return False, "stopped"
                time.sleep(0.001)
            self.blocked.clear()
        self.clock.sleep(self.step_s)
        if kind in self.failures:
            return False, self.failures[kind]
        return True, f"{kind} done"

    def move_named(self, group, name, speed, acceleration):
        return self._do("move_named", group, name, speed, acceleration)

    def move_relative(self, group, offset, frame, speed, acceleration):
        return self._do("move_relative", group, list(offset), frame, speed, acceleration)

    def move_pose(self, group, pose, speed, acceleration):
        return self._do("move_pose", group, list(pose), speed, acceleration)

    def tool(self, tool, action):
        return self._do("tool", tool, action)

    def run_routine(self, name):
        return self._do("routine", name)

    def stop(self):
        with self._lock:
            self.stops += 1
            if self.stop_releases or self.stops > 1:
                self._stopped.set()   # the move's call answers "stopped" at once, like the driver's ...
        time.sleep(self.stop_s)       # ... while its stop call answers once the arm stands still
        self.stop_returned = time.monotonic()
        return True, "stopped"

    def stop_routine(self):
        with self._lock:
            self.routine_stops += 1
        self._stopped.set()
        return True, "stopping"


class FakeTopics:
    def __init__(self) -> None:
        self.subscribers: dict[str, list[Callable[[Any], None]]] = {}
        self.latched: dict[str, Any] = {}

    def watch(self, topic: str, on_message: Callable[[Any], None]) -> Callable[[], None]:
        self.subscribers.setdefault(topic, []).append(on_message)
        if topic in self.latched:
            on_message(self.latched[topic])
        return lambda: self.subscribers[topic].remove(on_message)

    def publish(self, topic: str, msg: Any) -> None:
        for cb in list(self.subscribers.get(topic, [])):
            cb(msg)


class Harness:
    def __init__(self, cfg=None, step_s: float = 1.0) -> None:
        self.clock = FakeClock()
        self.robot = FakeRobot(self.clock, step_s)
        self.topics = FakeTopics()
        self.progress: list[Progress] = []
        self.log: list[tuple[str, str]] = []
        self.ex = Executor(cfg or config(), self.robot, self.clock, self.topics, self.progress.append,
                           self._on_log)
        self.result: Optional[RunResult] = None
        self.thread: Optional[threading.Thread] = None

    def _on_log(self, level: str, text: str) -> None:
        check_said(text)     # every line of every run here: its code and the app's catalogue agree
        self.log.append((level, text))

    def start(self, req: RunRequest) -> None:
        assert self.ex.begin(req) is None
        self.thread = threading.Thread(target=lambda: setattr(self, "result", self.ex.run(req)), daemon=True)
        self.thread.start()

    def join(self) -> RunResult:
        assert self.thread is not None
        self.thread.join(10)
        assert not self.thread.is_alive(), "the run did not end"
        assert self.result is not None
        return self.result

    def texts(self) -> list[str]:
        return [t for _, t in self.log]

    def state(self) -> str:
        return self.ex.progress().state


# ================================================================================================ section
def test_demo_cell_section_parses_with_the_demo_manual_section() -> None:
    cell = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    cfg = parse_cell_process(cell, {"approach_height": 100.0})
    assert cfg.action == "/cell/process/run" and cfg.start_configuration == "home"
    assert cfg.names == ["pick part", "place in fixture", "return home"]
    assert len(cfg.poses["part"]) == 3 and len(cfg.poses["pocket"]) == 3
    (start,) = cfg.start_targets
    assert (start.group, start.configuration) == ("arm", "home") and cfg.start_groups == ("arm",)
    assert start.joints == (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0) and start.indices == (0, 1, 2, 3, 4, 5)
    assert {s.group for op in cfg.operations for s in op.steps if isinstance(s, Tool)} == {"arm"}
    texts = [describe(s, 2, cfg.poses) for op in cfg.operations for s in op.steps]
    assert "Move to home" in texts and "Gripper close" in texts and "Move to part 2 (approach)" in texts
    assert "Move to pocket 2" in texts
    # The cell file's own texts per language: the node keeps the English, said as a step text the app translates.
    lift = next(t for t in texts if t == "Lift the part")
    assert coded(lift) == ("process.step_text", [("text", "Lift the part")])
    check_said(lift)
    assert "Move to part 2 (approach)" in texts


def test_a_step_text_per_language_keeps_the_english_and_needs_it() -> None:
    ops = [{"name": "op", "steps": [{"move_named": "home", "text": {"en": "Go {n} home", "es": "Ir a casa"}},
                                    {"move_pose": "part", "note": {"en": "slow", "fi": "hidas"}}]}]
    cfg = config(_with(operations=ops))
    assert [s.text for s in cfg.operations[0].steps] == ["Go {n} home", ""]
    assert cfg.operations[0].steps[1].note == "slow"
    with pytest.raises(ConfigError, match=r"steps\[0\]\.text\.en"):
        config(_with(operations=[{"name": "op", "steps": [{"move_named": "home", "text": {"es": "Ir a casa"}}]}]))


def test_section_fields() -> None:
    cfg = config()
    assert cfg.group == "arm" and cfg.tcp_speed == 0.2 and cfg.dry_run_step_s == 0.1
    step = cfg.operations[0].steps[2]
    assert isinstance(step, MovePose) and step.table == "part" and step.offset == (0, 0, 0.1, 0, 0, 0)
    assert step.note == "approach" and step.motion.group == "arm"
    assert cfg.operations[0].steps[0].motion.speed == 1.0
    assert cfg.start_tolerance == 0.01


def _with(**changes: Any) -> dict:
    s = yaml.safe_load(yaml.safe_dump(SECTION))
    s.update(changes)
    return s


def _steps(*steps: Any) -> dict:
    return _with(operations=[{"name": "op", "steps": list(steps)}])


@pytest.mark.parametrize("section, message", [
    (None, "process: the cell file has no process section"),
    (_with(operations=[]), "process.operations: expected a non-empty list"),
    (_with(operations=[{"name": "a", "steps": []}]), "process.operations[0].steps: expected a non-empty list"),
    (_with(operations=[{"name": "a", "steps": [{"wait_s": 1}]}, {"name": "a", "steps": [{"wait_s": 1}]}]),
     "process.operations[1].name: 'a' is used twice"),
    (_with(operations=[{"name": "a", "stpes": []}]), "process.operations[0]: unknown key 'stpes'"),
    (_steps({"move_named": "nowhere"}), "process.operations[0].steps[0].move_named: unknown configuration 'nowhere' "
                                        "for group arm (it has: home, pick_approach)"),
    (_steps({"move_named": "home", "group": "legs"}), "process.operations[0].steps[0].group: unknown motion group "
                                                      "'legs' (the robot driver has: arm)"),
    (_steps({"move_pose": "parts"}), "process.operations[0].steps[0].move_pose: no pose table 'parts' (the section "
                                     "has: part, pocket)"),
    (_steps({"move_pose": [1, 2, 3]}), "process.operations[0].steps[0].move_pose: expected a pose (or the name of a "
                                       "pose table) as 6 numbers"),
    (_steps({"move_pose": "part", "ofset": [0, 0, 0.1, 0, 0, 0]}),
     "process.operations[0].steps[0]: unknown key 'ofset' for a move_pose step"),
    (_steps({"move_relative": [0, 0, 0.1, 0, 0, "up"]}), "process.operations[0].steps[0].move_relative[5]: expected a "
                                                         "number, got 'up'"),
    (_steps({"move_relative": [0, 0, 0.1, 0, 0, 0], "frame": "world"}),
     "process.operations[0].steps[0].frame: expected base or tool, got 'world'"),
    (_steps({"tool": "gripper", "action": "crush"}), "process.operations[0].steps[0].action: unknown action 'crush' "
                                                     "for tool gripper (it has: open, close)"),
    (_steps({"tool": "vacuum", "action": "on"}), "process.operations[0].steps[0].tool: unknown tool 'vacuum'"),
    (_steps({"wait_s": -1}), "process.operations[0].steps[0].wait_s: must be at least 0, got -1"),
    (_steps({"wait_topic": "/x", "field": "data"}), "process.operations[0].steps[0]: a wait_topic step needs exactly "
                                                    "one condition of: equals, above, below"),
    (_steps({"wait_topic": "x", "field": "data", "equals": True}), "steps[0].wait_topic: expected a global topic"),
    (_steps({"wait_topic": "/x", "field": "data", "above": "high"}), "steps[0].above: expected a number"),
    (_steps({"wait_topic": "/x", "field": "data", "equals": 1, "timeout_s": 0}), "steps[0].timeout_s: must be above 0"),
    (_steps({"move_named": "home", "tool": "gripper"}), "process.operations[0].steps[0]: one kind per step, got "
                                                        "move_named and tool"),
    (_steps({"jump": 1}), "process.operations[0].steps[0]: unknown step ['jump'] (a step has one of: move_named, "
                          "move_relative, move_pose, tool, wait_s, wait_topic, routine)"),
    (_steps("home"), "process.operations[0].steps[0]: expected a step"),
    (_with(poses={"part": []}), "process.poses.part: expected a non-empty list of poses"),
    (_with(start_configuration="away"), "process.start_configuration: unknown configuration 'away'"),
    (_with(start_configuration={"arm": "away"}), "process.start_configuration.arm: unknown configuration 'away'"),
    (_with(start_configuration={"legs": "home"}), "process.start_configuration.legs: unknown motion group 'legs'"),
    (_with(start_configuration={}), "process.start_configuration: expected a configuration name or a mapping"),
    (_steps({"tool": "gripper", "action": "open", "group": "legs"}),
     "process.operations[0].steps[0].group: unknown motion group 'legs'"),
    (_with(tcp_speed=-1), "process.tcp_speed: must be above 0"),
])
def test_bad_sections_are_refused_naming_the_field(section: Any, message: str) -> None:
    with pytest.raises(ConfigError) as e:
        parse_process(section, MANUAL) if section is not None else parse_process(None)
    assert message in str(e.value)


def test_without_a_manual_section_references_are_not_checked() -> None:
    cfg = parse_process(_steps({"move_named": "anywhere"}, {"tool": "vacuum", "action": "on"}), None)
    assert cfg.group == "arm" and len(cfg.operations[0].steps) == 2


# ================================================================================================ steps
def test_step_texts() -> None:
    cfg = parse_process(_steps(
        {"move_named": "home"}, {"tool": "gripper", "action": "close"}, {"wait_s": 0.5},
        {"move_pose": "part", "offset": [0, 0, 0.08, 0, 0, 0], "note": "approach"},
        {"move_pose": [-0.45, -0.25, 0.1, 3.1416, 0, 0]},
        {"move_relative": [0, 0, 0.1, 0, 0, 0]}, {"move_relative": [0.05, 0, 0, 0, 0, 0.3], "frame": "tool"},
        {"wait_topic": "/x", "field": "data", "equals": True}, {"wait_topic": "/f", "field": "wrench.force.z",
                                                                 "below": -3.5},
        {"routine": "pick2"}, {"move_pose": "pocket", "text": "Into pocket {n}"}, {"wait_s": 1, "text": "Settle"}),
        MANUAL)
    texts = [describe(s, 2, cfg.poses) for s in cfg.operations[0].steps]
    assert texts == ["Move to home", "Gripper close", "Wait 0.5 s", "Move to part 2 (approach)",
                     "Move to pose (x -0.45, y -0.25, z 0.1)", "Move relative z +0.1 m",
                     "Move relative x +0.05 m, rz +0.3 rad (tool)", "Wait for /x data = true",
                     "Wait for /f wrench.force.z < -3.5", "Run routine pick2", "Into pocket 2", "Settle"]
    # Each says what it is with a code and parameters (the app's catalogue, process_said_<code>); the cell file's
    # own texts as a step text (the app finds them in the cell file's texts per language; {n} filled in).
    assert [coded(t)[0] for t in texts] == [
        "process.step_move_named", "process.step_tool", "process.step_wait", "process.step_move_table",
        "process.step_move_pose", "process.step_move_relative", "process.step_move_relative_tool",
        "process.step_wait_topic", "process.step_wait_topic", "process.step_routine", "process.step_text",
        "process.step_text"]
    assert coded(texts[10])[1] == [("text", "Into pocket 2")]
    assert coded(texts[3])[1] == [("table", "part"), ("n", "2"), ("note", " (approach)"),
                                  ("note.code", "process.step_note"), ("note.note", "approach")]
    assert coded(texts[1])[1] == [("tool", "Gripper"), ("action", "close")]
    for t in texts:
        check_said(t)


def test_pose_tables_index_by_cycle_and_wrap() -> None:
    cfg = config()
    assert [table_index(c, 3) for c in (1, 2, 3, 4, 7)] == [0, 1, 2, 0, 0]
    approach, at = cfg.operations[0].steps[2], cfg.operations[0].steps[3]
    assert resolve_pose(at, 1, cfg.poses) == [-0.44, -0.26, 0.032, 3.1416, 0, 0]
    assert resolve_pose(at, 5, cfg.poses) == [-0.48, -0.12, 0.032, 3.1416, 0, 0]  # (5 - 1) mod 3 = 1
    assert resolve_pose(approach, 3, cfg.poses) == pytest.approx([-0.44, 0.0, 0.132, 3.1416, 0, 0])
    pocket = cfg.operations[1].steps[1]
    assert resolve_pose(pocket, 3, cfg.poses)[:3] == [-0.35, 0.292, 0.042]       # 2 pockets: cycle 3 -> first
    assert describe(approach, 4, cfg.poses) == "Move to part 1 (approach)"


def test_a_rotating_offset_turns_about_the_tcp_in_the_base_frame() -> None:
    cfg = parse_process(_steps({"move_pose": [0.1, 0.2, 0.3, 0, 0, 0], "offset": [0, 0, 0.1, 0, 0, 1.0]}), MANUAL)
    assert resolve_pose(cfg.operations[0].steps[0], 1, cfg.poses) == pytest.approx([0.1, 0.2, 0.4, 0, 0, 1.0])


def test_conditions() -> None:
    msg = {"data": True, "pose": {"position": {"z": 0.25}}, "status": [{"level": 2}], "name": "ok"}
    assert field_value(msg, "pose.position.z") == 0.25 and field_value(msg, "status[0].level") == 2
    assert holds(True, "equals", True) and not holds(False, "equals", True) and holds(1, "equals", True)
    assert holds(0.3, "above", 0.25) and holds(0.2, "below", 0.25) and holds("ok", "equals", "ok")
    assert holds(2, "equals", 2.0) and not holds(3, "equals", 2)
    for path, why in (("dat", "the message has no field 'dat'"), ("status[3].level", "no element 3"),
                      ("pose..z", "bad field path")):
        with pytest.raises(ConditionError, match=why):
            field_value(msg, path)
    with pytest.raises(ConditionError, match="is not a number"):
        holds("ok", "above", 1)


# ================================================================================================ executor
ALL_KINDS = ["move_named", "tool", "move_pose", "move_pose", "tool", "move_relative",     # pick part
             "move_pose", "move_pose", "tool",                                          # place (+ a wait)
             "move_named"]                                                              # return home


def test_a_cycle_runs_every_step_in_order_with_texts_and_speeds() -> None:
    h = Harness()
    r = h.ex.execute(RunRequest(-1, 1))
    assert (r.success, r.message, r.state, r.cycles_done) == (True, "1 cycle done", IDLE, 1)
    assert h.robot.kinds() == ALL_KINDS
    calls = h.robot.calls
    assert calls[0] == ("move_named", "arm", "home", 1.0, 0.0)                       # the step's own speed
    assert calls[2] == ("move_pose", "arm", pytest.approx([-0.44, -0.26, 0.132, 3.1416, 0, 0]), 0.2, 0.0)  # default
    assert calls[3][3] == 0.1 and calls[5] == ("move_relative", "arm", [0, 0, 0.1, 0, 0, 0], "base", 0.2, 0.0)
    texts = h.texts()
    assert texts[0] == "Start: 1 cycle of 3 operations from cycle 1"
    assert texts[1:4] == ["Operation 'pick part' (cycle 1)", "Move to home", "Gripper open"]
    assert "Move to part 1 (approach)" in texts and "Wait 0.5 s" in texts
    assert "Operation 'place in fixture' done" in texts
    assert texts[-2] == "Cycle 1 done in 10.5 s" and texts[-1] == "Done: 1 cycle done"   # 10 calls of 1 s + 0.5 s
    assert r.last_cycle_s == pytest.approx(10.5)
    # Feedback: every step shows with its operation and index, then idle.
    steps = [(p.operation, p.step_index, p.step_count, p.step) for p in h.progress if p.state == RUNNING and p.step]
    assert steps[0] == (0, 0, 6, "Move to home") and steps[-1] == (2, 0, 1, "Move to home")
    assert (h.progress[-1].state, h.progress[-1].operation, h.progress[-1].cycles_done) == (IDLE, -1, 1)


def test_cycles_count_and_pose_tables_move_on() -> None:
    h = Harness()
    r = h.ex.execute(RunRequest(-1, 3, first_cycle=2))
    assert (r.success, r.cycles_done, r.message) == (True, 3, "3 cycles done")
    parts = [c[2][:2] for c in h.robot.calls if c[0] == "move_pose" and c[2][2] < 0.1 and c[2][1] < 0.2]
    assert parts == [[-0.48, -0.12], [-0.44, 0.0], [-0.44, -0.26]]     # cycles 2, 3, 4 -> entries 1, 2, 0
    assert [t for t in h.texts() if t.startswith("Cycle")] == [f"Cycle {c} done in 10.5 s" for c in (2, 3, 4)]
    assert max(p.cycles_done for p in h.progress) == 3


def test_cycling_until_stopped() -> None:
    h = Harness()
    h.start(RunRequest(-1, 0))
    wait_for(lambda: h.ex.progress().cycles_done >= 2, 10, what="two cycles")
    assert h.ex.stop() == (True, "stopped")
    r = h.join()
    assert (r.success, r.stopped, r.state) == (False, True, IDLE) and r.cycles_done >= 2
    assert h.texts()[0] == "Start: until stopped of 3 operations from cycle 1"


def test_pause_waits_for_the_step_end_holds_then_resume_continues_with_the_next_step() -> None:
    h = Harness()
    gate = h.robot.gate("tool")            # the second step (gripper open) blocks until released
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the tool step running")
    assert h.ex.pause() == (True, "pausing after the current step")
    assert h.state() == PAUSING and h.ex.pause()[1] == "already pausing: the current step finishes first"
    assert h.robot.kinds() == ["move_named", "tool"]
    del h.robot.gates["tool"]
    gate.set()                              # the step ends ...
    wait_for(lambda: h.state() == PAUSED, 5, what="paused")
    n = len(h.robot.calls)
    h.clock.sleep(30)                       # ... and nothing moves while paused
    time.sleep(0.05)
    assert len(h.robot.calls) == n == 2 and h.robot.stops == 0
    assert "Paused after 'Gripper open'; next: 'Move to part 1 (approach)'" in h.texts()
    assert h.ex.resume() == (True, "resumed")
    r = h.join()
    assert r.success and h.robot.kinds() == ALL_KINDS          # the paused step is not run again
    assert "Resumed: next 'Move to part 1 (approach)'" in h.texts()
    states = [p.state for p in h.progress]
    assert states.index(PAUSING) < states.index(PAUSED) < len(states) - 1 - states[::-1].index(RUNNING)


def test_resume_while_pausing_cancels_the_pause_and_resume_when_not_paused_is_refused() -> None:
    h = Harness()
    assert h.ex.resume() == (False, "the process is not running")
    assert h.ex.pause() == (False, "the process is not running")
    gate = h.robot.gate("move_named")
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the first step running")
    assert h.ex.resume() == (False, "the process is not paused")
    h.ex.pause()
    assert h.ex.resume() == (True, "pause cancelled: the run goes on") and h.state() == RUNNING
    del h.robot.gates["move_named"]
    gate.set()
    assert h.join().success and PAUSED not in [p.state for p in h.progress]


def test_stop_mid_step_stops_the_robot_at_once() -> None:
    h = Harness()
    h.robot.gate("move_pose")              # a move that only ends when the driver is stopped
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the approach move running")
    assert h.ex.stop() == (True, "stopped")
    r = h.join()
    assert h.robot.stops == 1 and h.robot.kinds() == ["move_named", "tool", "move_pose"]
    assert (r.success, r.stopped, r.state, r.message) == (False, True, IDLE, "stopped by the operator")
    assert STOPPING in [p.state for p in h.progress] and h.progress[-1].state == IDLE
    assert h.texts()[-1] == "Stopped during 'Move to part 1 (approach)': stopped by the operator"
    assert not h.ex.active and h.ex.stop() == (True, "the process is not running")


def test_the_run_ends_only_once_the_drivers_stop_answered() -> None:
    h = Harness()
    h.robot.gate("move_named")
    h.robot.stop_s = 0.3
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the first step running")
    threading.Thread(target=h.ex.stop, daemon=True).start()
    r = h.join()
    ended = time.monotonic()
    assert r.stopped and h.robot.stop_returned and ended >= h.robot.stop_returned


def test_stop_while_paused_ends_the_run() -> None:
    h = Harness()
    gate = h.robot.gate("move_named")
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the first step running")
    h.ex.pause()
    del h.robot.gates["move_named"]
    gate.set()
    wait_for(lambda: h.state() == PAUSED, 5, what="paused")
    h.ex.stop()
    r = h.join()
    assert r.stopped and h.robot.kinds() == ["move_named"]


def test_a_move_that_reaches_the_driver_after_the_stop_is_stopped_again() -> None:
    h = Harness()
    h.robot.gate("move_pose")
    h.robot.stop_releases = False          # the first stop comes too early for this move
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the approach move running")
    assert h.ex.stop() == (True, "stopped")
    assert h.robot.stops == 2 and h.join().stopped


def test_one_operation_runs_once() -> None:
    h = Harness()
    r = h.ex.execute(RunRequest(1, 1, first_cycle=2))
    assert (r.success, r.message, r.cycles_done) == (True, "operation 'place in fixture' done", 1)
    assert h.robot.kinds() == ["move_pose", "move_pose", "tool"]
    assert h.robot.calls[1][2][:3] == [-0.35, 0.35, 0.042]             # cycle 2: the second pocket
    assert h.texts()[0] == "Start: operation 'place in fixture' once"
    assert not any(t.startswith("Cycle") for t in h.texts()) and r.last_cycle_s == 0


def test_dry_run_makes_no_robot_call() -> None:
    h = Harness()
    r = h.ex.execute(RunRequest(-1, 2, dry_run=True))
    assert r.success and r.cycles_done == 2
    assert h.robot.calls == [] and h.robot.stops == 0
    assert "Dry run: Move to home" in h.texts() and "Dry run: Move to part 2 (approach)" in h.texts()
    assert h.texts()[0].endswith("(dry run: no robot motion)")
    assert r.last_cycle_s == pytest.approx(11 * 0.1)


def test_a_failing_step_ends_the_run_in_error_with_the_drivers_message() -> None:
    h = Harness()
    h.robot.fail("move_pose", "pose unreachable: no inverse kinematics solution")
    r = h.ex.execute(RunRequest(-1, 3))
    message = "Move to part 1 (approach) failed: pose unreachable: no inverse kinematics solution"
    assert (r.success, r.state, r.message, r.cycles_done) == (False, ERROR, message, 0)
    assert (r.operation, r.step_index, r.step) == (0, 2, "Move to part 1 (approach)")
    assert h.robot.kinds() == ["move_named", "tool", "move_pose"] and h.robot.stops == 1   # the arm stopped
    assert h.log[-1] == ("error", f"Error: {message}")
    last = h.progress[-1]
    assert (last.state, last.operation, last.step_index, last.message) == (ERROR, 0, 2, message)
    # the executor is free again
    h.robot.failures.clear()
    assert h.ex.execute(RunRequest(2, 1)).success


def test_an_exception_from_the_transport_is_a_failed_step() -> None:
    h = Harness()

    def boom(*_a: Any) -> tuple[bool, str]:
        raise RuntimeError("service /cell/manual/tool went away")

    h.robot.tool = boom  # type: ignore[method-assign]
    r = h.ex.execute(RunRequest(-1, 1))
    assert r.state == ERROR and r.message == "Gripper open failed: service /cell/manual/tool went away"


def test_abort_ends_in_error() -> None:
    h = Harness()
    h.robot.gate("move_named")
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the first step running")
    h.ex.abort("the cell went into alarm (alarms): the run was stopped")
    r = h.join()
    assert (r.state, r.stopped, r.message) == (ERROR, False, "the cell went into alarm (alarms): the run was stopped")
    assert h.robot.stops == 1 and h.progress[-1].state == ERROR


def test_refusals() -> None:
    h = Harness()
    assert h.ex.refusal(RunRequest(3, 1)) == ("no operation 3 (the process has 3: 0 pick part, 1 place in fixture, "
                                              "2 return home)")
    h.robot.gate("move_named")
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="running")
    assert h.ex.begin(RunRequest(-1, 1)) == "the process is already running: stop it first"
    r = h.ex.execute(RunRequest(0, 1))
    assert (r.success, r.message) == (False, "the process is already running: stop it first")
    h.ex.stop()
    h.join()


def _wait_section(**cond: Any) -> Any:
    return parse_process(_steps({"wait_topic": "/cell/door", "field": "data", "timeout_s": 5, **cond},
                                {"move_named": "home"}), MANUAL)


def test_wait_topic_continues_once_the_condition_holds() -> None:
    h = Harness(_wait_section(equals=True))
    h.start(RunRequest(-1, 1))
    wait_for(lambda: h.topics.subscribers.get("/cell/door"), 5, what="the subscription")
    h.topics.publish("/cell/door", {"data": False})
    time.sleep(0.02)
    assert h.robot.calls == []
    h.topics.publish("/cell/door", {"data": True})
    assert h.join().success and h.robot.kinds() == ["move_named"]
    assert h.topics.subscribers["/cell/door"] == []       # unsubscribed after the step
    assert "Wait for /cell/door data = true" in h.texts()


def test_wait_topic_accepts_a_latched_value_and_times_out_clearly() -> None:
    h = Harness(_wait_section(above=0.5))
    h.topics.latched["/cell/door"] = {"data": 0.7}
    assert h.ex.execute(RunRequest(-1, 1)).success
    h = Harness(_wait_section(above=0.5))
    h.topics.latched["/cell/door"] = {"data": 0.2}
    r = h.ex.execute(RunRequest(-1, 1))
    assert r.message == "Wait for /cell/door data > 0.5 failed: /cell/door data was 0.2, not > 0.5, for 5 s"
    h = Harness(_wait_section(equals="open"))
    r = h.ex.execute(RunRequest(-1, 1))
    assert r.message == "Wait for /cell/door data = open failed: no message on /cell/door within 5 s"
    h = Harness(parse_process(_steps({"wait_topic": "/cell/door", "field": "dta", "equals": 1}), MANUAL))
    h.topics.latched["/cell/door"] = {"data": 1}
    r = h.ex.execute(RunRequest(-1, 1))
    assert r.message == "Wait for /cell/door dta = 1 failed: /cell/door: the message has no field 'dta'"


def test_routines_run_stop_and_rerun_after_a_pause() -> None:
    cfg = parse_process(_steps({"routine": "pick2"}, {"move_named": "home"}), MANUAL)
    h = Harness(cfg)
    assert h.ex.execute(RunRequest(-1, 1)).success and h.robot.kinds() == ["routine", "move_named"]
    # Pause during the routine: it is stopped (the routines node has no pause) and runs again on resume.
    h = Harness(cfg)
    h.robot.gate("routine")
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the routine running")
    assert h.ex.pause() == (True, "pausing: the routine was stopped")
    wait_for(lambda: h.state() == PAUSED, 5, what="paused")
    assert h.robot.routine_stops == 1 and h.robot.stops == 0
    del h.robot.gates["routine"]
    h.ex.resume()
    assert h.join().success and h.robot.kinds() == ["routine", "routine", "move_named"]
    # Stop during the routine: the routine and the arm are stopped.
    h = Harness(cfg)
    h.robot.gate("routine")
    h.start(RunRequest(-1, 1))
    wait_for(h.robot.blocked.is_set, 5, what="the routine running")
    h.ex.stop()
    assert h.join().stopped and (h.robot.routine_stops, h.robot.stops) == (1, 1)


def test_dry_run_stop_needs_no_driver() -> None:
    h = Harness()
    h.start(RunRequest(-1, 0, dry_run=True))
    wait_for(lambda: h.ex.progress().step_index >= 1, 5, what="walking")
    assert h.ex.stop() == (True, "stopped (dry run: no robot motion to stop)")
    assert h.join().stopped and h.robot.stops == 0


# ================================================================================================ mode
MODES = ["idle", "running", "paused", "alarm", "programming", "manual"]


def test_the_mode_follows_the_process_but_never_leaves_alarm() -> None:
    f = ModeFollower(MODES)
    f.on_mode("idle", "startup")
    assert f.refusal() is None
    assert f.transition(RUNNING) == "running"
    f.on_set("running", True)
    assert f.transition(PAUSING) is None                 # still running
    assert f.transition(PAUSED) == "paused"
    f.on_set("paused", True)
    assert f.transition(RUNNING) == "running"
    f.on_set("running", True)
    assert f.transition(STOPPING) is None
    assert f.transition(IDLE) == "idle"
    f.on_set("idle", True)
    # An alarm during a run: start refused, the mode stays alarm when the run ends in error.
    assert f.transition(RUNNING) == "running"
    f.on_mode("alarm", "alarms")
    assert f.in_alarm() and f.refusal() == "the cell is in alarm: reset it first"
    assert f.transition(ERROR) is None and not f.wanted("idle")
    # The alarms node gives `running` back once the alarm cleared: the idle process corrects it.
    f.on_mode("running", "alarms")
    assert f.correction(active=False) == "idle" and f.correction(active=True) is None
    f.on_mode("manual", "ui:alice")
    assert f.correction(active=False) is None            # an operator's mode stays
    f.on_mode("running", "process")                      # left by a previous run (node restarted)
    assert f.correction(active=False) == "idle"


def test_modes_the_cell_does_not_list_are_not_set() -> None:
    f = ModeFollower(["idle", "running"])
    f.on_mode("idle", "startup")
    assert f.transition(RUNNING) == "running"
    assert f.transition(PAUSED) is None


# ================================================================================================ client
def client(**kw: Any) -> tuple[ProcessClient, FakeClock]:
    clock = FakeClock()
    c = ProcessClient(config(), clock=clock.now, **kw)
    c.ready = True
    c.on_mode("idle")
    return c, clock


def test_client_refusals() -> None:
    c, _ = client()
    c.on_mode("alarm")
    assert c.start(1) == (None, "the cell is in alarm: reset it first")
    c.on_mode("idle")
    c.ready = False
    assert c.start(1) == (None, "the process server is not running (its action server does not answer)")
    c.ready = True
    assert c.step_request(5)[1] == "no operation 5 (the process has 3: 0 pick part, 1 place in fixture, 2 return home)"
    req, _ = c.start(2)
    assert req == RunRequest(-1, 2, False, 1) and c.state == RUNNING and c.run_mode == "cycle"
    assert c.start(1) == (None, "the process is already running: stop it first")
    assert c.step_request(0) == (None, "the process is already running: stop it first")
    assert c.set_dry_run(True) == (False, "the process is running: change the dry run once it is stopped")
    c.state = PAUSED
    assert c.start(1)[1] == "the process is paused: resume or stop it"
    assert [t.text for t in c.log.entries()][:2] == ["Start refused: the cell is in alarm: reset it first",
                                                     "Start refused: the process server is not running (its action "
                                                     "server does not answer)"]
    broken = ProcessClient(None, "process.operations: expected a non-empty list")
    broken.ready = True
    assert broken.start(1)[1] == "the process cannot run: process.operations: expected a non-empty list"
    assert broken.view().state == ERROR


def test_client_state_from_feedback_and_results_and_the_cycle_counter() -> None:
    c, clock = client()
    req, _ = c.start(0)
    c.on_feedback(Progress(RUNNING, 0, 2, 6, "Move to part 1 (approach)", 1, 0, clock.now() - 3, 0, "running"))
    v = c.view()
    assert (v.state, v.current, v.step_index, v.step_count, v.step) == (RUNNING, 0, 2, 6, "Move to part 1 (approach)")
    assert v.cycle_time_s == pytest.approx(3) and v.cycles_target == 0 and v.run_mode == "cycle"
    c.on_feedback(Progress(PAUSED, 0, 3, 6, "Move to part 1", 2, 1, clock.now(), 12.5, "running"))
    assert (c.view().state, c.view().cycle, c.view().last_cycle_s) == (PAUSED, 2, 12.5)
    assert c.stop_request() == (True, "stopping") and c.state == STOPPING
    c.on_feedback(Progress(RUNNING, 0, 3, 6, "Move to part 1", 2, 1, clock.now(), 12.5, ""))
    assert c.state == STOPPING                        # the stop is on its way
    c.on_result(RunResult(False, "stopped by the operator", IDLE, True, 1, 12.5))
    v = c.view()
    assert (v.state, v.message, v.cycle, v.cycles_done, v.current, v.run_mode) == (
        IDLE, "stopped by the operator", 2, 1, -1, "")   # cycle 2 was interrupted: the next start repeats it
    c.on_feedback(Progress(RUNNING, 1, 0, 4, "late", 2, 1, 0, 0, ""))
    assert c.view().state == IDLE                     # late feedback of an ended run
    req, _ = c.start(1)
    assert req.first_cycle == 2
    c.on_result(RunResult(True, "1 cycle done", IDLE, False, 1, 11.0))
    assert c.next_cycle == 3 and c.view().last_cycle_s == 11.0
    # Step runs do not count, except the last operation, which completes the cycle.
    req, _ = c.step_request(0)
    assert req == RunRequest(0, 1, False, 3) and c.run_mode == "step"
    c.on_result(RunResult(True, "operation 'pick part' done", IDLE, False, 1))
    assert c.next_cycle == 3
    c.step_request(2)
    c.on_result(RunResult(True, "operation 'return home' done", IDLE, False, 1))
    assert c.next_cycle == 4
    # An error shows where it happened.
    c.start(1)
    c.on_result(RunResult(False, "Gripper close failed: x", ERROR, False, 0, 0, 0, 4, "Gripper close"))
    v = c.view()
    assert (v.state, v.current, v.step_index, v.step, v.message) == (ERROR, 0, 4, "Gripper close",
                                                                     "Gripper close failed: x")
    assert c.start(1)[0] is not None                  # an error does not block the next start
    c.on_rejected("the cell is in alarm: reset it first")
    assert (c.state, c.message, c.active) == (IDLE, "the cell is in alarm: reset it first", False)


def test_client_lost_server_and_stop_when_idle() -> None:
    c, _ = client()
    assert c.stop_request() == (False, "the process is not running")
    c.start(1)
    c.on_lost("the process server stopped answering during the run")
    assert (c.state, c.active) == (ERROR, False)
    assert c.log.entries()[-1].text == "Error: the process server stopped answering during the run"


def test_client_dry_run_and_at_start() -> None:
    c, _ = client()
    assert c.set_dry_run(True) == (True, "dry run on: the process walks its steps without moving the robot")
    assert c.set_dry_run(True) == (True, "dry run is already on")
    assert c.start(1)[0].dry_run
    assert not c.at_start()                           # joints unknown
    c.on_joints([0.005, -1.5708, 1.5708, -1.5708, -1.5708, -0.009])
    assert c.at_start() and c.view().start_configuration == "home"
    c.on_joints([0.02, -1.5708, 1.5708, -1.5708, -1.5708, 0.0])
    assert not c.at_start()
    no_start = ProcessClient(parse_process(_with(start_configuration=""), MANUAL))
    assert no_start.at_start()                        # nothing to confirm


def test_client_log_keeps_the_last_200_newest_last() -> None:
    c, _ = client()
    for i in range(250):
        c.note("info", f"line {i}")
    lines = c.log.entries()
    assert len(lines) == LOG_SIZE and lines[0].text == "line 50" and lines[-1].text == "line 249"
    assert c.log.added == 250


# ---- parameter references (the parameters CSV, read at start) ----

def test_parameter_references_take_the_csv_values_scaled() -> None:
    from cell_nodes.process.config import substitute_parameters, parse_cell_process
    section = {"operations": [{"name": "a", "steps": [
        {"move_relative": [0, 0, {"parameter": "h", "scale": 0.001}, 0, 0, 0]}, {"wait_s": {"parameter": "w"}}]}]}
    out = substitute_parameters(section, {"h": 120.0, "w": 2})
    assert out["operations"][0]["steps"][0]["move_relative"][2] == pytest.approx(0.12)
    assert out["operations"][0]["steps"][1]["wait_s"] == 2.0
    cfg = parse_cell_process({"process": section}, {"h": 50, "w": 0.5})
    assert cfg.operations[0].steps[0].offset[2] == pytest.approx(0.05)


def test_a_bad_parameter_reference_names_the_field() -> None:
    from cell_nodes.process.config import ConfigError, substitute_parameters
    section = {"operations": [{"steps": [{"wait_s": {"parameter": "nope"}}]}]}
    with pytest.raises(ConfigError, match=r"process\.operations\[0\]\.steps\[0\]\.wait_s\.parameter: unknown parameter 'nope'"):
        substitute_parameters(section, {"h": 1})
    with pytest.raises(ConfigError, match="not a number"):
        substitute_parameters({"x": {"parameter": "name"}}, {"name": "text"})


def test_the_demo_cell_reads_its_approach_height_from_the_parameters_csv(tmp_path, monkeypatch) -> None:
    from pathlib import Path
    from cell_nodes.cell_file import load_cell
    from cell_nodes.process.config import parse_cell_process
    monkeypatch.setenv("DATA_DIR", str(tmp_path))
    (tmp_path / "parameters.csv").write_text("id,value\napproach_height,80\n")
    cell = load_cell(str(Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"))
    approach = parse_cell_process(cell).operations[0].steps[2]
    assert approach.offset[2] == pytest.approx(0.08)



def test_a_new_start_takes_the_parameters_as_saved_now_and_a_running_run_keeps_its_own(tmp_path, monkeypatch) -> None:
    """What the process server does at each start: parse the cell's process again (the CSV as saved now) and hand it
    to begin(), which adopts it only for a run it accepts."""
    from pathlib import Path
    from cell_nodes.cell_file import load_cell
    from cell_nodes.process.config import parse_cell_process
    monkeypatch.setenv("DATA_DIR", str(tmp_path))
    csv = tmp_path / "parameters.csv"
    cell = load_cell(str(Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"))
    approach_z = lambda cfg: cfg.operations[0].steps[2].offset[2]   # noqa: E731 - pick part: the approach pose
    csv.write_text("id,value\napproach_height,80\n")
    h = Harness(parse_cell_process(cell), step_s=0.0)
    gate = h.robot.gate("move_named")
    csv.write_text("id,value\napproach_height,120\n")   # saved on the Parameters page before Start
    assert h.ex.begin(RunRequest(0, 1), parse_cell_process(cell)) is None
    assert approach_z(h.ex.config) == pytest.approx(0.12)
    h.thread = threading.Thread(target=lambda: setattr(h, "result", h.ex.run(RunRequest(0, 1))), daemon=True)
    h.thread.start()
    wait_for(h.robot.blocked.is_set, 5, what="running")
    # Saved while it runs: a start now is refused and the run goes on with the values it started with.
    csv.write_text("id,value\napproach_height,30\n")
    assert h.ex.begin(RunRequest(0, 1), parse_cell_process(cell)) == "the process is already running: stop it first"
    gate.set()
    assert h.join().success
    part = cell["process"]["poses"]["part"][0]
    approach = next(c[2] for c in h.robot.calls if c[0] == "move_pose")
    assert math.dist(approach[:3], part[:3]) == pytest.approx(0.12, abs=1e-6)
    assert h.ex.begin(RunRequest(0, 1), parse_cell_process(cell)) is None
    assert approach_z(h.ex.config) == pytest.approx(0.03)

# ================================================================================================ two arms
TWIN_MANUAL = {
    "groups": [
        {"name": "left", "host": "127.0.2.1", "joints": [f"left_{j}" for j in ("shoulder_pan_joint", "shoulder_lift_joint",
                                                                               "elbow_joint", "wrist_1_joint",
                                                                               "wrist_2_joint", "wrist_3_joint")],
         "configurations": {"home": [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0],
                            "handover": [1.0, -1.2, 1.6, -1.97, -1.5708, 0.4]}},
        # a group of some joints, in another order: the indices come from the UR names the joints end with
        {"name": "right", "host": "127.0.2.2", "joints": ["right_wrist_3_joint", "right_shoulder_pan_joint"],
         "configurations": {"home": [0.5, -0.5], "out": [0.0, 1.0]}}],
    "tools": [{"name": "gripper", "actions": [{"name": "close", "steps": [{"wait_s": 0.1}]}]},
              {"name": "vacuum", "group": "right", "actions": [{"name": "on", "steps": [{"wait_s": 0.1}]}]}],
}
LEFT_HOME = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]


def twin_section(**changes: Any) -> dict:
    s = {"group": "left", "start_configuration": {"left": "home", "right": "home"},
         "operations": [{"name": "hand over", "steps": [
             {"move_named": "handover"}, {"tool": "gripper", "action": "close"},
             {"move_named": "out", "group": "right"}, {"tool": "vacuum", "action": "on"},
             {"tool": "vacuum", "action": "on", "group": "right"}]}]}
    s.update(changes)
    return s


def test_start_configuration_per_group_and_tool_steps_on_their_tools_group() -> None:
    cfg = parse_process(twin_section(), TWIN_MANUAL)
    assert cfg.start_configuration == "left: home, right: home" and cfg.start_groups == ("left", "right")
    left, right = cfg.start_targets
    assert (left.indices, left.joints) == ((0, 1, 2, 3, 4, 5), tuple(LEFT_HOME))
    assert (right.indices, right.joints) == ((5, 0), (0.5, -0.5))
    steps = cfg.operations[0].steps
    assert [s.motion.group for s in steps if not isinstance(s, Tool)] == ["left", "right"]
    assert [(s.tool, s.group) for s in steps if isinstance(s, Tool)] == [("gripper", "left"), ("vacuum", "right"),
                                                                         ("vacuum", "right")]
    with pytest.raises(ConfigError, match=r"^process\.operations\[0\]\.steps\[0\]\.group: tool vacuum is on "
                                          r"group right \(manual\.tools\), not left$"):
        parse_process(twin_section(operations=[{"name": "x", "steps": [
            {"tool": "vacuum", "action": "on", "group": "left"}]}]), TWIN_MANUAL)
    # a name: the configuration of process.group, as before
    named = parse_process(twin_section(start_configuration="handover"), TWIN_MANUAL)
    assert named.start_configuration == "handover" and named.start_groups == ("left",)


def test_at_start_needs_every_listed_group_there() -> None:
    c = ProcessClient(parse_process(twin_section(), TWIN_MANUAL))
    assert not c.at_start()                                  # nothing known
    c.on_joints(LEFT_HOME, "left")
    assert not c.at_start()                                  # the right arm still unknown
    right = [-0.5, 9.0, 9.0, 9.0, 9.0, 0.5]                  # only its joints 6 and 1 count (0.5, -0.5)
    c.on_joints(right, "right")
    assert c.at_start() and c.view().at_start and c.view().start_configuration == "left: home, right: home"
    c.on_joints([-0.5, 0, 0, 0, 0, 0.52], "right")           # right's wrist 3 off by 0.02 rad
    assert not c.at_start()
    c.on_joints(right, "right")
    c.on_joints([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.02], "left")
    assert not c.at_start()
    only_left = ProcessClient(parse_process(twin_section(start_configuration={"left": "home"}), TWIN_MANUAL))
    only_left.on_joints(LEFT_HOME, "left")
    assert only_left.at_start()                              # the right arm is not asked about
    by_name = ProcessClient(parse_process(twin_section(start_configuration="home"), TWIN_MANUAL))
    by_name.on_joints(LEFT_HOME)                             # no group: process.group
    assert by_name.at_start()


# ================================================================================================ cycle times, restarts
def test_a_cycles_active_time_excludes_the_paused_time_and_its_elapsed_time_includes_it() -> None:
    h = Harness()
    gate = h.robot.gate("tool")            # cycle 1's second step blocks until released
    h.start(RunRequest(-1, 2))
    wait_for(h.robot.blocked.is_set, 5, what="the tool step running")
    assert h.ex.pause()[0]
    del h.robot.gates["tool"]
    gate.set()
    wait_for(lambda: h.state() == PAUSED, 5, what="paused")
    p = h.ex.progress()
    assert p.paused_since > 0 and p.cycle_paused_s == 0
    active, elapsed = p.cycle_times(h.clock.now())
    assert active == pytest.approx(2.0)                     # two steps of 1 s: pausing is still the step's time
    h.clock.sleep(30)                                       # a long pause
    active2, elapsed2 = h.ex.progress().cycle_times(h.clock.now())
    assert active2 == pytest.approx(2.0) and elapsed2 >= elapsed + 30
    assert h.ex.resume() == (True, "resumed")
    r = h.join()
    assert r.success
    first = next(p for p in h.progress if p.cycles_done == 1)
    assert first.last_cycle_s == pytest.approx(10.5)        # as without the pause (10 steps of 1 s + a 0.5 s wait)
    assert first.last_cycle_elapsed_s >= 40.5
    assert first.paused_since == 0 and first.cycle_paused_s >= 30
    cycle_lines = [t for t in h.texts() if t.startswith("Cycle")]
    assert re.fullmatch(r"Cycle 1 done in 10\.5 s \(4\d\.\d s with pauses\)", cycle_lines[0]), cycle_lines
    assert cycle_lines[1] == "Cycle 2 done in 10.5 s"       # no pause: one figure
    assert (r.last_cycle_s, r.last_cycle_elapsed_s) == (pytest.approx(10.5), pytest.approx(10.5))
    assert h.progress[-1].paused_since == 0


def test_client_shows_active_and_elapsed_cycle_times_and_its_counter_survives_a_restart() -> None:
    c, clock = client()
    c.start(0)
    t = clock.now()
    c.on_feedback(Progress(RUNNING, 0, 1, 6, "Gripper open", 1, 0, t - 10, 0, "running", cycle_paused_s=4.0))
    v = c.view()
    assert (v.cycle_time_s, v.cycle_elapsed_s) == (pytest.approx(6), pytest.approx(10))
    c.on_feedback(Progress(PAUSED, 0, 1, 6, "Gripper open", 1, 0, t - 10, 0, "running", cycle_paused_s=4.0,
                           paused_since=t - 2))
    clock.sleep(5)                                          # still paused: only the elapsed time goes on
    v = c.view()
    assert (v.cycle_time_s, v.cycle_elapsed_s) == (pytest.approx(4), pytest.approx(15))
    # Cycle 1 completes: the counter moves on at once, with both times.
    c.on_feedback(Progress(RUNNING, 0, 0, 6, "Move to home", 2, 1, clock.now(), 12.0, "running",
                           last_cycle_elapsed_s=19.0))
    v = c.view()
    assert (c.next_cycle, v.cycle, v.last_cycle_s, v.last_cycle_elapsed_s) == (2, 2, 12.0, 19.0)
    assert c.memory() == {"next_cycle": 2, "last_cycle_s": 12.0, "last_cycle_elapsed_s": 19.0}
    # The nodes restart (mid-run even): the new client takes the saved memory back, through its JSON file.
    d, _ = client()
    assert d.restore(json.loads(json.dumps(c.memory()))) is None
    v = d.view()
    assert (v.state, v.cycle, v.cycles_done, v.last_cycle_s, v.last_cycle_elapsed_s, v.cycle_time_s) == (
        IDLE, 2, 0, 12.0, 19.0, 0.0)
    assert d.start(1)[0].first_cycle == 2                  # the interrupted cycle 2 runs again, not cycle 1
    # Without a memory (what a restart did before): counting from 1 again.
    assert client()[0].view().cycle == 1
    c.on_result(RunResult(False, "stopped by the operator", IDLE, True, 1, 12.0, last_cycle_elapsed_s=19.0))
    v = c.view()
    assert (v.cycle, v.cycle_time_s, v.cycle_elapsed_s, v.last_cycle_elapsed_s) == (2, 0.0, 0.0, 19.0)
    # An older server without the elapsed field: the active time stands for both.
    c.start(1)
    c.on_result(RunResult(True, "1 cycle done", IDLE, False, 1, 11.0))
    assert (c.view().last_cycle_s, c.view().last_cycle_elapsed_s, c.next_cycle) == (11.0, 11.0, 3)


@pytest.mark.parametrize("change, why", [
    ({"next_cycle": 0}, r"next_cycle: expected a whole number from 1 to 4294967295, got 0"),
    ({"next_cycle": 2.5}, r"next_cycle: expected a whole number"),
    ({"next_cycle": True}, r"next_cycle: expected a whole number"),
    ({"next_cycle": 2 ** 32}, r"next_cycle: expected a whole number"),
    ({"last_cycle_s": -1}, r"last_cycle_s: expected a number of seconds"),
    ({"last_cycle_s": "10"}, r"last_cycle_s: expected a number of seconds"),
    ({"last_cycle_elapsed_s": None}, r"last_cycle_elapsed_s: expected a number of seconds"),
    ({"last_cycle_elapsed_s": 5.0}, r"last_cycle_elapsed_s \(5\.0\) is below last_cycle_s \(12\.0\)"),
])
def test_client_refuses_a_malformed_memory_and_counts_from_1(change: dict, why: str) -> None:
    memory = dict({"next_cycle": 7, "last_cycle_s": 12.0, "last_cycle_elapsed_s": 19.0}, **change)
    assert re.search(why, memory_problem(memory))
    c, _ = client()
    assert re.search(why, c.restore(memory))
    assert c.memory() == {"next_cycle": 1, "last_cycle_s": 0.0, "last_cycle_elapsed_s": 0.0}


def test_texts_per_language_are_the_pages_the_node_keeps_the_english():
    """An operation's title and a status field's label may be given per language (the page shows them); the node
    takes the operation by its name and the label in English."""
    cfg = parse_process(_with(
        operations=[{"name": "op", "title": {"en": "Pick", "es": "Recoger"}, "steps": [{"move_named": "home"}]}],
        status_fields=[{"label": {"en": "Cycles done", "fi": "Jaksoja tehty"}, "topic": "/cell/process/state", "field": "cycles_done"}],
    ), MANUAL)
    assert [o.name for o in cfg.operations] == ["op"]
    assert cfg.status_fields[0].label == "Cycles done"
    with pytest.raises(ConfigError, match=r"status_fields\[0\]\.label\.en"):
        parse_process(_with(status_fields=[{"label": {"es": "Ciclos"}, "topic": "/t", "field": "f"}]), MANUAL)


def test_said_texts_nest_their_codes_and_stay_strings() -> None:
    inner = say("process.count_cycle", "3 cycles", count=3)
    outer = say("process.done_cycles", "{cycles} done", cycles=inner)
    assert outer == "3 cycles done" and isinstance(outer, str)
    assert coded(outer) == ("process.done_cycles", [("cycles", "3 cycles"), ("cycles.code", "process.count_cycle"),
                                                    ("cycles.count", "3")])
    assert coded("plain") == ("", [])
    assert coded(outer + "!") == ("", []), "a text made from it is plain English"


def test_the_run_log_lines_carry_codes() -> None:
    h = Harness()
    h.start(RunRequest(-1, 1))
    h.join()
    lines = [t for _, t in h.log]
    assert coded(lines[0]) == ("process.start_cycles", [
        ("cycles", "1 cycle"), ("cycles.code", "process.count_cycle"), ("cycles.count", "1"),
        ("operations", "3 operations"), ("operations.code", "process.count_operation"), ("operations.count", "3"),
        ("cycle", "1"), ("dry", "")])
    assert lines[0] == "Start: 1 cycle of 3 operations from cycle 1"
    assert coded(lines[1])[0] == "process.operation" and coded(lines[2])[0] == "process.step_move_named"
    done = lines[-1]
    assert done == "Done: 1 cycle done" and coded(done)[0] == "process.done"
    assert ("result.code", "process.done_cycles") in coded(done)[1]


class _Status:
    def __init__(self, active: int, alarm_id: str = "", text: str = "", code: str = "", params=()) -> None:
        self.active_count, self.alarm_id, self.text, self.code = active, alarm_id, text, code
        self.params = [type("KV", (), {"key": k, "value": v})() for k, v in params]


def test_a_run_ended_by_the_alarm_mode_names_the_alarm() -> None:
    named = alarm_reason("alarms", _Status(1, "robot.arm.protective_stop", "Robot arm: protective stop",
                                           "robot.safety.protective_stop", [("group", "arm")]))
    assert named == ("the cell went into alarm (alarms): robot.arm.protective_stop: Robot arm: protective stop; "
                     "the run was stopped")
    code, params = coded(named)
    assert code == "process.reason_alarm_named"
    assert ("alarm.code", "alarm.robot.safety.protective_stop") in params and ("alarm.group", "arm") in params
    # No status yet, or no active alarm in it: the source only.
    for status in (None, _Status(0)):
        plain = alarm_reason("", status)
        assert plain == "the cell went into alarm (unknown): the run was stopped"
        assert coded(plain)[0] == "process.reason_alarm"
        check_said(plain)
    check_said(named)


def test_the_clients_own_log_lines_carry_codes() -> None:
    c, _ = client()
    c.on_mode("alarm")
    c.start(1)
    c.on_mode("idle")
    c.ready = False
    c.step_request(0)
    c.ready = True
    c.set_dry_run(True)
    c.start(1)
    c.set_dry_run(False)
    c.on_lost("the process server stopped answering during the run")
    lines = [e.text for e in c.log.entries()]
    assert [coded(t)[0] for t in lines] == ["process.start_refused", "process.step_refused", "process.dry_on",
                                            "process.dry_change_refused", "process.error"]
    for t in lines:
        check_said(t)
