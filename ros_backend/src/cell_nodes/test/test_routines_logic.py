"""Routines, the plain-Python logic (no ROS, no robot): the cell file section, routine names, the file store (atomic
save and reload, duplicates, rename, delete, unreadable files in the list), recording against a fake robot, and the
runner (the sequence, stop mid-run, a failing step, one run at a time)."""
from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path
from typing import Optional, Sequence

import pytest
import yaml

from cell_nodes.routines import store as store_module
from cell_nodes.routines.config import ConfigError, RoutinesConfig, parse_routines, routines_dir
from cell_nodes.routines.core import Routines
from cell_nodes.routines.log import LogBook
from cell_nodes.routines.model import (ACTION, POSE, Routine, RoutineError, Step, check_name, checked, decode,
                                       encode, format_pose, name_problem)
from cell_nodes.routines.runner import IDLE, RUNNING, STOPPING, RunState, Runner
from cell_nodes.routines.store import RoutineStore
from conftest import wait_for
from said_check import check_said

ROOT = Path(__file__).resolve().parents[4]
DEMO = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
P1 = (0.4123, -0.12, 0.2305, 3.1416, 0.0, 0.0)
P2 = (0.35, 0.05, 0.3, 3.1416, 0.0, 0.0)
J = (0.0, -1.57, 1.57, -1.57, -1.57, 0.0)


def config() -> RoutinesConfig:
    return parse_routines(DEMO)


def steps() -> list[Step]:
    return [Step(POSE, P1, J), Step(ACTION, tool="gripper", action="close"), Step(POSE, P2)]


class FakeRobot:
    """The driver's services: moves take `move_s` unless stopped; a pose listed in `fail` is refused."""

    def __init__(self, move_s: float = 0.0) -> None:
        self.move_s = move_s
        self.calls: list[tuple] = []
        self.fail: dict[tuple[float, ...], str] = {}
        self.pose_answer: tuple[bool, str, list[float], list[float]] = (True, "pose of arm", list(J), list(P1))
        self.moving = threading.Event()
        self._stopped = threading.Event()
        self.stops = 0

    def get_pose(self, group: str) -> tuple[bool, str, list[float], list[float]]:
        self.calls.append(("get_pose", group))
        return self.pose_answer

    def _motion(self, label: str) -> tuple[bool, str]:
        self._stopped.clear()
        self.moving.set()
        try:
            if self._stopped.wait(self.move_s):
                return False, "stopped"
            return True, label
        finally:
            self.moving.clear()

    def move_pose(self, group: str, pose: Sequence[float], speed: float, acceleration: float) -> tuple[bool, str]:
        self.calls.append(("move_pose", group, tuple(pose), speed, acceleration))
        if tuple(pose) in self.fail:
            return False, self.fail[tuple(pose)]
        return self._motion("arrived at the pose target")

    def tool(self, tool: str, action: str) -> tuple[bool, str]:
        self.calls.append(("tool", tool, action))
        return self._motion(f"{tool} {action} done")

    def stop(self) -> tuple[bool, str]:
        self.stops += 1
        self._stopped.set()
        return True, "stopped"


def make(tmp_path: Path, robot: Optional[FakeRobot] = None, cfg: Optional[RoutinesConfig] = None):
    robot = robot or FakeRobot()
    log = LogBook()
    add = log.add

    def checked_add(level: str, text: str) -> None:
        check_said(text)  # every log line of every test here: its code and the app's catalogues agree
        add(level, text)
    log.add = checked_add  # type: ignore[method-assign]
    r = Routines(cfg or config(), RoutineStore(str(tmp_path / "routines")), robot, log)
    states: list[RunState] = []

    def on_state(s: RunState) -> None:
        check_said(s.message)
        states.append(s)
    r.runner.on_state = on_state
    return r, robot, log, states


def texts(log: LogBook) -> list[str]:
    return [e.text for e in log.entries()]


# ================================================================ the cell file section
def test_section_of_the_demo_cell() -> None:
    c = config()
    assert c.directory == "routines" and c.groups == {"arm": 6} and c.tools == {"gripper": ("open", "close", "check_part")}
    assert c.speed == 0.1 and c.acceleration == 0.0 and c.warnings == ()


def test_section_defaults_and_unknown_names() -> None:
    cell = {"manual": DEMO["manual"], "routines": {"groups": ["arm", "legs"], "tools": ["gripper", "drill"]}}
    c = parse_routines(cell)
    assert list(c.groups) == ["arm"] and list(c.tools) == ["gripper"]
    assert c.warnings == ("routines.groups[1]: 'legs' is not a motion group of the robot driver (manual.groups: arm); "
                          "ignored", "routines.tools[1]: 'drill' is not a tool of the robot driver (manual.tools: "
                          "gripper); ignored")
    c = parse_routines({"manual": DEMO["manual"], "routines": {}})
    assert c.directory == "routines" and list(c.groups) == ["arm"] and c.tools == {} and c.speed == 0.0


@pytest.mark.parametrize("directory", ["/etc", "../up", "a/../../b", ".."])
def test_a_directory_outside_data_dir_is_refused(directory: str) -> None:
    with pytest.raises(ConfigError, match="routines.directory: .* must be a path inside DATA_DIR"):
        parse_routines({"routines": {"directory": directory}})


def test_routines_dir_from_data_dir(monkeypatch, tmp_path: Path) -> None:
    monkeypatch.setenv("DATA_DIR", str(tmp_path))
    assert routines_dir(config()) == str(tmp_path / "routines")
    monkeypatch.delenv("DATA_DIR")
    monkeypatch.chdir(tmp_path)
    assert routines_dir(config()) == str(tmp_path / ".data" / "routines")


# ================================================================ names
@pytest.mark.parametrize("name", ["pick2", "Pick and place", "a", "x" * 64, "v1.2_final-B", "-dash", "a.json",
                                  "a..b"])
def test_good_names(name: str) -> None:
    assert name_problem(name) is None


@pytest.mark.parametrize("name,problem", [
    ("a/b", "invalid routine name 'a/b': use letters, digits, space, - _ ."),
    ("a\\b", "invalid routine name 'a\\\\b': use letters, digits, space, - _ ."),
    ("../etc/passwd", "invalid routine name '../etc/passwd': use letters, digits, space, - _ ."),
    ("..", "invalid routine name '..': it must not start with a dot"),
    (".", "invalid routine name '.': it must not start with a dot"),
    (".hidden", "invalid routine name '.hidden': it must not start with a dot"),
    ("", "a routine needs a name"),
    ("x" * 65, "routine name '" + "x" * 65 + "' is too long (65 characters, at most 64)"),
    (" lead", "invalid routine name ' lead': it must not start or end with a space"),
    ("trail ", "invalid routine name 'trail ': it must not start or end with a space"),
    ("Greifer schließen", "invalid routine name 'Greifer schließen': use letters, digits, space, - _ ."),
    ("a\nb", "invalid routine name 'a\\nb': use letters, digits, space, - _ ."),
    ("nul\0", "invalid routine name 'nul\\x00': use letters, digits, space, - _ ."),
    ("tab\tx", "invalid routine name 'tab\\tx': use letters, digits, space, - _ ."),
    ("C:x", "invalid routine name 'C:x': use letters, digits, space, - _ ."),
])
def test_bad_names(name: str, problem: str) -> None:
    assert name_problem(name) == problem
    check_said(name_problem(name))
    with pytest.raises(RoutineError):
        check_name(name)


def test_a_very_long_name_is_cut_in_the_message() -> None:
    problem = name_problem("y" * 10000)
    assert problem is not None and "10000 characters, at most 64" in problem and len(problem) < 200


# ================================================================ checks and the file format
def test_checked_normalises_and_names_the_bad_step() -> None:
    c = config()
    r = checked(c, "pick2", "arm", "gripper", [Step(POSE, P1, J, tool="x", action="y"), Step(ACTION, action="close")])
    assert r.steps == (Step(POSE, P1, J), Step(ACTION, tool="gripper", action="close"))
    bad = [
        (("pick2", "arm", "", []), "a routine needs at least one step"),
        (("pick2", "", "", steps()), "a routine needs a motion group (routines.groups: arm)"),
        (("pick2", "legs", "", steps()), "unknown motion group 'legs' for routines (routines.groups: arm)"),
        (("pick2", "arm", "drill", steps()), "unknown tool 'drill' for routines (routines.tools: gripper)"),
        (("pick2", "arm", "", [Step(POSE, P1[:5])]),
         "step 1: a pose needs 6 finite numbers (x, y, z in m, rx, ry, rz in rad), got 5 values"),
        (("pick2", "arm", "", [Step(POSE, (float("nan"),) + P1[1:])]),
         "step 1: a pose needs 6 finite numbers (x, y, z in m, rx, ry, rz in rad), got 6 values (not all finite)"),
        (("pick2", "arm", "", [Step(POSE, P1, (0.0, 1.0))]),
         "step 1: joints must be empty or the group's 6 joint positions, got 2 values"),
        (("pick2", "arm", "gripper", [Step(POSE, P1), Step(ACTION, action="grab")]),
         "step 2: unknown action 'grab' for tool gripper (it has: open, close, check_part)"),
        (("pick2", "arm", "", [Step(ACTION, action="close")]),
         "step 1: a tool action needs a tool (routines.tools: gripper)"),
        (("pick2", "arm", "", [Step(ACTION, tool="drill", action="on")]),
         "step 1: unknown tool 'drill' for routines (routines.tools: gripper)"),
        (("pick2", "arm", "", [Step("jump")]), "step 1: unknown step kind 'jump' (pose or action)"),
        (("pick2", "arm", "gripper", [Step(ACTION, tool="gripper")]),
         "step 1: an action step needs an action (one of the tool's actions)"),
        (("pick2", "arm", "", [Step(POSE, P1)] * 1001), "too many steps (1001, at most 1000)"),
        (("a/b", "arm", "", steps()), "invalid routine name 'a/b': use letters, digits, space, - _ ."),
    ]
    for args, message in bad:
        with pytest.raises(RoutineError) as e:
            checked(c, *args)
        assert str(e.value) == message


def test_encode_decode_round_trip_exactly() -> None:
    r = checked(config(), "pick2", "arm", "gripper", steps())
    data = encode(r)
    doc = json.loads(data)
    assert doc["version"] == 1 and "name" not in doc and doc["steps"][1] == {"kind": "action", "tool": "gripper",
                                                                              "action": "close"}
    back = decode("pick2", data, 12.5)
    assert back == Routine("pick2", "arm", "gripper", r.steps, 12.5)
    with pytest.raises(ValueError):
        encode(Routine("x", "arm", "", (Step(POSE, (float("inf"),) * 6),)))


@pytest.mark.parametrize("data,error", [
    (b"{", "the file is not valid JSON (Expecting property name enclosed in double quotes at line 1, column 2)"),
    (b"", "the file is not valid JSON (Expecting value at line 1, column 1)"),
    (b"\xff\xfe", "the file is not UTF-8 text"),
    (b"[]", "the file is not a routine (expected a JSON object)"),
    (b'{"version": 2, "group": "arm", "steps": []}', "unsupported routine file version 2 (this node reads 1)"),
    (b'{"version": 1, "group": 3, "steps": []}', "the file's group and tool must be text"),
    (b'{"version": 1, "group": "arm"}', "the file has no list of steps"),
    (b'{"version": 1, "group": "arm", "steps": [1]}', "step 1 in the file is not an object"),
    (b'{"version": 1, "group": "arm", "steps": [{"kind": "pose", "pose": "up"}]}',
     "step 1 in the file has fields of the wrong type"),
    (b'{"version": 1, "group": "arm", "steps": [{"kind": "pose", "pose": [1, 2]}]}',
     "step 1 in the file: a pose needs 6 finite numbers (x, y, z in m, rx, ry, rz in rad), got 2 values"),
    (b'{"version": 1, "group": "arm", "steps": [{"kind": "pose", "pose": [1, 2, 3, 4, 5, true]}]}',
     "step 1 in the file: a pose needs 6 finite numbers (x, y, z in m, rx, ry, rz in rad), got 6 values "
     "(not all finite)"),
])
def test_decode_says_what_is_wrong_with_a_file(data: bytes, error: str) -> None:
    with pytest.raises(RoutineError) as e:
        decode("x", data)
    assert str(e.value) == error
    check_said(e.value.args[0])   # said with a code, in every catalogue
    assert e.value.args[0].code.startswith("routines.file_")


def test_format_pose() -> None:
    assert format_pose((0.4123, -0.12, 0.2305, 3.14159, -0.0, -0.00001)) == \
        "x 412.3, y -120.0, z 230.5 mm, rx 3.142, ry 0.000, rz 0.000 rad"


# ================================================================ the store
def test_atomic_save_and_reload(tmp_path: Path, monkeypatch) -> None:
    store = RoutineStore(str(tmp_path / "deep" / "routines"))
    assert store.list() == []
    synced: list[int] = []
    real_fsync = os.fsync
    monkeypatch.setattr(store_module.os, "fsync", lambda fd: (synced.append(fd), real_fsync(fd))[1])
    r = checked(config(), "pick2", "arm", "gripper", steps())
    assert store.save(r, overwrite=False) is False
    assert len(synced) == 2  # the file's data, then the directory (the rename)
    path = tmp_path / "deep" / "routines" / "pick2.json"
    assert sorted(os.listdir(path.parent)) == ["pick2.json"]  # no temp file left
    assert oct(path.stat().st_mode & 0o777) == "0o644"
    got = store.read("pick2")
    assert got.error == "" and got.steps == r.steps and got.group == "arm" and got.tool == "gripper"
    assert abs(got.modified - path.stat().st_mtime) < 1e-6
    assert RoutineStore(str(path.parent)).list() == [got]  # a new store (a restarted node) reads the same


def test_a_failed_write_leaves_the_old_file_and_no_temp_file(tmp_path: Path, monkeypatch) -> None:
    store = RoutineStore(str(tmp_path))
    old = checked(config(), "pick2", "arm", "", [Step(POSE, P1)])
    store.save(old, overwrite=False)

    def broken_fsync(fd: int) -> None:
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(store_module.os, "fsync", broken_fsync)
    with pytest.raises(RoutineError, match="cannot save routine 'pick2': No space left on device"):
        store.save(checked(config(), "pick2", "arm", "", [Step(POSE, P2)]), overwrite=True)
    assert os.listdir(tmp_path) == ["pick2.json"] and store.read("pick2").steps == old.steps


def test_duplicates_and_overwrite(tmp_path: Path) -> None:
    r, _, log, _ = make(tmp_path)
    assert r.save("pick2", "arm", "gripper", steps(), False) == (True, "routine pick2 saved (3 steps)")
    assert r.save("pick2", "arm", "", [Step(POSE, P2)], False) == (False, "a routine named 'pick2' exists already")
    assert r.save("pick2", "arm", "", [Step(POSE, P2)], True) == (True, "routine pick2 replaced (1 step)")
    assert r.store.read("pick2").steps == (Step(POSE, P2),)
    assert texts(log) == ["Routine pick2 saved (3 steps)", "Routine pick2 replaced (1 step)"]


def test_refusals_are_said_with_codes_nested_to_their_cause(tmp_path: Path) -> None:
    """Issue 29: a refused save, rename, delete or run is said with a code, its cause nested, so the app says all of
    it in the user's language (said_check: every catalogue has it, with the same parameters)."""
    r, *_ = make(tmp_path)
    assert r.save("pick2", "arm", "", [Step(POSE, P2)], False)[0]
    answers = [r.save("pick2", "arm", "", [Step(POSE, P2)], False)[1],
               r.save("new", "arm", "", [Step(POSE, P2), Step(ACTION, tool="drill", action="close")], False)[1],
               r.save("new", "arm", "", [], False)[1], r.save(" new", "arm", "", [Step(POSE, P2)], False)[1],
               r.rename("pick2", "pick2")[1], r.delete("ghost")[1], r.run("ghost")[1]]
    assert [a.code for a in answers] == ["routines.exists", "routines.step_problem", "routines.steps_needed",
                                         "routines.name_space", "routines.same_name", "routines.no_such",
                                         "routines.no_such"]
    step = dict(answers[1].params)
    assert (step["step"], step["why.code"], step["why.tool"]) == ("2", "routines.tool_unknown", "'drill'")
    for a in answers:
        check_said(a)


def test_temp_files_and_foreign_files_are_not_routines(tmp_path: Path) -> None:
    store = RoutineStore(str(tmp_path))
    store.save(checked(config(), "a", "arm", "", [Step(POSE, P1)]), overwrite=False)
    for junk in (".tmp-x1.json", ".hidden.json", "notes.txt", "bad name!.json"):
        (tmp_path / junk).write_text("{}")
    (tmp_path / "sub.json").mkdir()
    assert [(x.name, x.error) for x in store.list()] == [("a", ""), ("sub", "sub.json is not a regular file")]
    assert store.remove_temp_files() == 1 and not (tmp_path / ".tmp-x1.json").exists()


def test_rename_and_delete(tmp_path: Path) -> None:
    r, _, log, _ = make(tmp_path)
    r.save("pick2", "arm", "gripper", steps(), False)
    r.save("place", "arm", "", [Step(POSE, P2)], False)
    assert r.rename("pick2", "pick3") == (True, "routine pick2 renamed to pick3")
    assert [x.name for x in r.list()[2]] == ["pick3", "place"]
    assert r.store.read("pick3").steps == checked(config(), "x", "arm", "gripper", steps()).steps
    assert r.rename("pick3", "place") == (False, "a routine named 'place' exists already")
    assert r.store.read("pick3").error == "" and r.store.read("place").steps == (Step(POSE, P2),)  # both intact
    assert r.rename("nothing", "else") == (False, "no routine named 'nothing'")
    assert r.rename("pick3", "pick3") == (False, "routine 'pick3' has that name already")
    assert r.rename("pick3", "../x") == (False, "invalid routine name '../x': use letters, digits, space, - _ .")
    assert r.rename("../x", "y") == (False, "invalid routine name '../x': use letters, digits, space, - _ .")
    assert r.delete("place") == (True, "routine place deleted")
    assert r.delete("place") == (False, "no routine named 'place'")
    assert r.delete("/etc/passwd") == (False, "invalid routine name '/etc/passwd': use letters, digits, space, - _ .")
    assert r.delete(".") == (False, "invalid routine name '.': it must not start with a dot")
    assert [x.name for x in r.list()[2]] == ["pick3"]
    assert texts(log) == ["Routine pick2 saved (3 steps)", "Routine place saved (1 step)",
                          "Routine pick2 renamed to pick3", "Routine place deleted"]


def test_a_corrupt_file_is_listed_with_its_error_and_the_others_still_load(tmp_path: Path, monkeypatch) -> None:
    r, _, _, _ = make(tmp_path)
    r.save("b good", "arm", "gripper", steps(), False)
    d = tmp_path / "routines"
    (d / "a broken.json").write_text('{"version": 1, "group": "arm", "steps": [')
    (d / "c old tool.json").write_text(json.dumps({"version": 1, "group": "arm", "tool": "",
                                                  "steps": [{"kind": "action", "tool": "drill", "action": "on"}]}))
    (d / "D.json").write_text(json.dumps({"version": 1, "group": "arm", "tool": "", "steps": [
        {"kind": "pose", "pose": list(P1), "joints": []}]}))
    (d / "e unreadable.json").write_text("{}")
    real_open = open

    def no_permission(path, *args, **kwargs):  # chmod 0 would not stop root, who runs these tests in CI
        if str(path).endswith("e unreadable.json"):
            raise PermissionError(13, "Permission denied")
        return real_open(path, *args, **kwargs)
    monkeypatch.setattr(store_module, "open", no_permission, raising=False)
    (d / "f dangling.json").symlink_to(d / "nowhere.json")
    ok, message, found = r.list()
    assert ok and message == "6 routines"
    by_name = {x.name: x for x in found}
    assert [x.name for x in found] == ["a broken", "b good", "c old tool", "D", "e unreadable", "f dangling"]
    assert by_name["a broken"].error.startswith("a broken.json: the file is not valid JSON (") and \
        by_name["a broken"].steps == ()
    assert by_name["b good"].error == "" and len(by_name["b good"].steps) == 3 and by_name["b good"].modified > 0
    # Well formed but not runnable here: the steps are shown, with why it cannot run.
    assert by_name["c old tool"].error == ("cannot run with this cell file: step 1: unknown tool 'drill' for "
                                           "routines (routines.tools: gripper)")
    assert len(by_name["c old tool"].steps) == 1
    assert by_name["D"].error == ""
    assert by_name["e unreadable"].error == "cannot read e unreadable.json: Permission denied"
    assert by_name["f dangling"].error == "f dangling.json is a link to nothing"
    # Said with codes (issue 29): the Routines page says why in the user's language, the cause nested.
    assert [by_name[n].error.code for n in ("a broken", "c old tool", "e unreadable", "f dangling")] == [
        "routines.file_problem", "routines.not_runnable", "routines.file_unreadable", "routines.file_dangling"]
    assert dict(by_name["a broken"].error.params)["why.code"] == "routines.file_not_json"
    for x in found:
        if x.error:
            check_said(x.error)
    assert r.run("a broken")[1].startswith("routine a broken cannot run: a broken.json: the file is not valid JSON")
    assert r.run("c old tool") == (False, "routine c old tool cannot run with this cell file: step 1: unknown tool "
                                          "'drill' for routines (routines.tools: gripper)")


def test_an_unusable_directory_is_an_answer_not_a_crash(tmp_path: Path) -> None:
    (tmp_path / "routines").write_text("a file where the directory should be")
    r, _, _, _ = make(tmp_path)
    ok, message, found = r.list()
    assert not ok and message.startswith("cannot read the routines directory ") and found == []
    ok, message = r.save("x", "arm", "", [Step(POSE, P1)], False)
    assert not ok and message.startswith("cannot write in the routines directory ")


# ================================================================ recording
def test_record_a_pose_and_an_action(tmp_path: Path) -> None:
    r, robot, log, _ = make(tmp_path)
    ok, message, step = r.record("arm", "", "pose", "")
    assert ok and step == Step(POSE, P1, J) and robot.calls == [("get_pose", "arm")]
    assert message == "Pose recorded: x 412.3, y -120.0, z 230.5 mm, rx 3.142, ry 0.000, rz 0.000 rad"
    assert r.record("", "gripper", "action", "close") == (True, "Gripper close recorded",
                                                           Step(ACTION, tool="gripper", action="close"))
    assert texts(log) == [message, "Gripper close recorded"]
    assert r.list()[2] == []  # nothing stored


def test_record_refusals(tmp_path: Path) -> None:
    r, robot, log, _ = make(tmp_path)
    assert r.record("legs", "", "pose", "") == (False, "unknown motion group 'legs' for routines (routines.groups: "
                                                       "arm)", None)
    assert r.record("arm", "gripper", "action", "grab") == (False, "unknown action 'grab' for tool gripper (it has: "
                                                                   "open, close, check_part)", None)
    assert r.record("arm", "drill", "action", "on") == (False, "unknown tool 'drill' for routines (routines.tools: "
                                                               "gripper)", None)
    assert r.record("arm", "", "wave", "") == (False, "unknown step kind 'wave' (pose or action)", None)
    robot.pose_answer = (False, "robot controller at 127.0.0.1 is unreachable", [], [])
    assert r.record("arm", "", "pose", "") == (False, "cannot read the pose: robot controller at 127.0.0.1 is "
                                                      "unreachable", None)
    robot.pose_answer = (True, "pose of arm", [], [])
    assert r.record("arm", "", "pose", "") == (False, "the robot driver answered no TCP pose", None)

    def boom(group: str):
        raise RuntimeError("connection reset")
    robot.get_pose = boom  # type: ignore[method-assign]
    assert r.record("arm", "", "pose", "") == (False, "cannot read the pose: the robot driver call failed: "
                                                      "connection reset", None)
    assert texts(log) == []


# ================================================================ the runner
def test_run_in_sequence(tmp_path: Path) -> None:
    r, robot, log, states = make(tmp_path)
    r.save("pick2", "arm", "gripper", steps(), False)
    assert r.run("pick2") == (True, "routine pick2 done")
    assert robot.calls == [("move_pose", "arm", P1, 0.1, 0.0), ("tool", "gripper", "close"),
                           ("move_pose", "arm", P2, 0.1, 0.0)]
    assert [(s.state, s.step, s.total) for s in states] == [(RUNNING, 0, 3), (RUNNING, 1, 3), (RUNNING, 2, 3),
                                                            (RUNNING, 3, 3), (IDLE, 0, 3)]
    assert states[1].message == "step 1 of 3: pose x 412.3, y -120.0, z 230.5 mm"
    assert states[-1] == RunState("pick2", IDLE, 0, 3, "routine pick2 done")
    assert texts(log)[1:] == ["Routine pick2 started (3 steps, group arm)",
                              "Step 1 of 3 reached: pose x 412.3, y -120.0, z 230.5 mm",
                              "Step 2 of 3 done: gripper close",
                              "Step 3 of 3 reached: pose x 350.0, y 50.0, z 300.0 mm",
                              "Routine pick2 done"]
    assert r.run("nothing") == (False, "no routine named 'nothing'")
    assert r.run("a/b") == (False, "invalid routine name 'a/b': use letters, digits, space, - _ .")
    assert texts(log)[-1] == "Run refused: invalid routine name 'a/b': use letters, digits, space, - _ ."


def test_a_failing_step_ends_the_run_with_its_message(tmp_path: Path) -> None:
    r, robot, log, states = make(tmp_path)
    robot.fail[P2] = "pose unreachable: no inverse kinematics solution"
    r.save("pick2", "arm", "gripper", steps() + [Step(POSE, P1)], False)
    ok, message = r.run("pick2")
    assert not ok and message == ("step 3 of 4 (pose x 350.0, y 50.0, z 300.0 mm) failed: pose unreachable: no "
                                  "inverse kinematics solution")
    assert [c[0] for c in robot.calls] == ["move_pose", "tool", "move_pose"]  # step 4 never started
    assert states[-1] == RunState("pick2", IDLE, 0, 4, message)
    assert log.entries()[-1].level == "error" and texts(log)[-1] == f"Routine pick2 failed: {message}"


def test_stop_mid_run(tmp_path: Path) -> None:
    r, robot, log, states = make(tmp_path, FakeRobot(move_s=10.0))
    r.save("pick2", "arm", "gripper", steps(), False)
    result: list[tuple[bool, str]] = []
    t = threading.Thread(target=lambda: result.append(r.run("pick2")))
    t.start()
    wait_for(robot.moving.is_set, 5, what="the first move under way")
    # One run at a time, and no file change under a running routine.
    assert r.run("pick2") == (False, "routine pick2 is running: stop it first")
    assert texts(log)[-1] == "Run refused: routine pick2 is running: stop it first"
    assert r.delete("pick2") == (False, "routine pick2 is running: stop it first")
    assert r.rename("pick2", "x") == (False, "routine pick2 is running: stop it first")
    assert r.save("pick2", "arm", "", [Step(POSE, P1)], True) == (False, "routine pick2 is running: stop it first")
    t0 = time.monotonic()
    assert r.stop() == (True, "routine pick2 stopped")
    assert time.monotonic() - t0 < 1.0
    t.join(5)
    assert result == [(False, "stopped")] and robot.stops == 1
    assert [c[0] for c in robot.calls] == ["move_pose"]
    assert [s.state for s in states][-2:] == [STOPPING, IDLE] and states[-1].message == "routine pick2 stopped"
    assert texts(log)[-1] == "Routine pick2 stopped at step 1 of 3" and log.entries()[-1].level == "warning"
    assert r.stop() == (True, "no routine is running")
    assert robot.stops == 1  # nothing to stop: the driver is left alone


def test_a_stop_from_elsewhere_ends_the_run(tmp_path: Path) -> None:
    """The page's "Stop robot" calls the driver directly: the step's call answers "stopped" and the run ends."""
    r, robot, log, _ = make(tmp_path, FakeRobot(move_s=10.0))
    r.save("pick2", "arm", "gripper", steps(), False)
    result: list[tuple[bool, str]] = []
    t = threading.Thread(target=lambda: result.append(r.run("pick2")))
    t.start()
    wait_for(robot.moving.is_set, 5, what="the first move under way")
    robot.stop()
    t.join(5)
    assert result == [(False, "stopped")] and len(robot.calls) == 1
    assert texts(log)[-1] == "Routine pick2 stopped at step 1 of 3"


def test_stop_between_steps_starts_no_further_step(tmp_path: Path) -> None:
    """The driver's answer arrives, then stop: the next step must not start even though no call was cut short."""
    robot = FakeRobot()
    r, _, _, _ = make(tmp_path, robot)
    r.save("pick2", "arm", "gripper", steps(), False)
    entered, release = threading.Event(), threading.Event()
    real_tool = robot.tool

    def slow_answer(tool: str, action: str) -> tuple[bool, str]:
        answer = real_tool(tool, action)
        entered.set()
        release.wait(5)
        return answer
    robot.tool = slow_answer  # type: ignore[method-assign]
    result: list[tuple[bool, str]] = []
    t = threading.Thread(target=lambda: result.append(r.run("pick2")))
    t.start()
    assert entered.wait(5)
    stopper = threading.Thread(target=r.stop)
    stopper.start()
    wait_for(lambda: r.runner.state().state == STOPPING, 5, what="stopping")
    release.set()
    t.join(5)
    stopper.join(5)
    assert result == [(False, "stopped")] and [c[0] for c in robot.calls] == ["move_pose", "tool"]


def test_a_driver_that_raises_fails_the_step_and_the_runner_stays_usable(tmp_path: Path) -> None:
    r, robot, _, _ = make(tmp_path)
    r.save("pick2", "arm", "gripper", steps(), False)

    def boom(*args: object) -> tuple[bool, str]:
        raise ConnectionError("driver gone")
    robot.move_pose = boom  # type: ignore[method-assign]
    assert r.run("pick2") == (False, "step 1 of 3 (pose x 412.3, y -120.0, z 230.5 mm) failed: the robot driver "
                                     "call failed: driver gone")
    assert r.runner.state().state == IDLE and r.runner.running() == ""


def test_log_keeps_the_last_200_newest_last() -> None:
    seen: list[int] = []
    log = LogBook()
    log.on_change = lambda entries: seen.append(len(entries))
    for i in range(205):
        log.info(f"entry {i}")
    entries = log.entries()
    assert len(entries) == 200 and entries[0].text == "entry 5" and entries[-1].text == "entry 204"
    assert seen[-1] == 200 and len(seen) == 205
    assert all(a.stamp <= b.stamp for a, b in zip(entries, entries[1:]))


# ================================================================ two arms: a routine uses its group's tools
TWIN = {
    "manual": {
        "groups": [{"name": "left", "host": "127.0.2.1", "joints": ["left_elbow_joint", "left_wrist_3_joint"]},
                   {"name": "right", "host": "127.0.2.2", "joints": ["right_elbow_joint"]}],
        "tools": [{"name": "gripper", "actions": [{"name": "close", "steps": [{"wait_s": 0}]}]},
                  {"name": "vacuum", "group": "right", "actions": [{"name": "on", "steps": [{"wait_s": 0}]}]}]},
    "routines": {"groups": ["left", "right"], "tools": ["gripper", "vacuum"]},
}


def test_tools_belong_to_their_group() -> None:
    c = parse_routines(TWIN)
    assert c.groups == {"left": 2, "right": 1} and c.tool_groups == {"gripper": "left", "vacuum": "right"}
    assert c.warnings == ()
    only_left = parse_routines({**TWIN, "routines": {"groups": ["left"], "tools": ["gripper", "vacuum"]}})
    assert list(only_left.tools) == ["gripper"]
    assert only_left.warnings == ("routines.tools[1]: tool 'vacuum' is on group 'right' (manual.tools), which "
                                  "routines.groups does not offer (left); ignored",)


def test_record_save_and_run_for_one_group_with_its_tools(tmp_path: Path) -> None:
    r, robot, log, _ = make(tmp_path, cfg=parse_routines(TWIN))
    robot.pose_answer = (True, "pose of right", [0.3], list(P1))
    ok, _, pose = r.record("right", "", "pose", "")
    assert ok and pose == Step(POSE, P1, (0.3,)) and robot.calls == [("get_pose", "right")]
    assert r.record("right", "vacuum", "action", "on")[0]
    assert r.record("right", "gripper", "action", "close") == (
        False, "tool gripper is on group left, not right (a routine uses its group's tools: vacuum)", None)
    assert r.save("bad", "right", "", [pose, Step(ACTION, tool="gripper", action="close")], False) == (
        False, "step 2: tool gripper is on group left, not right (a routine uses its group's tools: vacuum)")
    assert r.save("bad", "left", "vacuum", [pose], False) == (
        False, "tool vacuum is on group right, not left (a routine uses its group's tools: gripper)")
    assert r.save("suck", "right", "vacuum", [pose, Step(ACTION, action="on")], False)[0]
    robot.calls.clear()
    assert r.run("suck") == (True, "routine suck done")
    assert robot.calls == [("move_pose", "right", P1, 0.0, 0.0), ("tool", "vacuum", "on")]
