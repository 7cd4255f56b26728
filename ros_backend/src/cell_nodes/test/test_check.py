"""The cell file check (python -m cell_nodes.check, run by `npm run check-config` after the schema): no ROS. The demo
cell passes; each mistake the JSON Schema lets through but a node's (or the sim's) own parser refuses is reported
with its field path, one line per section, all sections in one run; an unreadable file exits with 2."""
from __future__ import annotations

import copy
import re
from pathlib import Path
from typing import Any, Callable

import pytest
import yaml

from cell_nodes.check import EXIT_OK, EXIT_PROBLEMS, EXIT_UNREADABLE, Report, check_cell, check_manual, main

DEMO = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"
_DEMO_DOC = yaml.safe_load(DEMO.read_text(encoding="utf-8"))


def demo() -> dict[str, Any]:
    return copy.deepcopy(_DEMO_DOC)


def steps(d: dict, op: int = 0) -> list:
    return d["process"]["operations"][op]["steps"]


def items(d: dict) -> list:
    return d["parameters"]["items"]


def test_the_demo_cell_passes(capsys) -> None:
    report = check_cell(demo(), str(DEMO))
    assert report.problems == []
    assert report.warnings == []
    assert main([str(DEMO)]) == EXIT_OK
    assert capsys.readouterr().out == ""


def _set_param(d: dict, **kw: Any) -> None:
    items(d)[0].update(kw)


# (name, mutation, the one line expected): each passes the JSON Schema (npm run check-config before this check).
MISTAKES: list[tuple[str, Callable[[dict], None], str]] = [
    ("unknown configuration", lambda d: steps(d)[0].update(move_named="hom"),
     r"^process\.operations\[0\]\.steps\[0\]\.move_named: unknown configuration 'hom' for group arm \(it has: home, "),
    ("unknown tool", lambda d: steps(d)[1].update(tool="grip"),
     r"^process\.operations\[0\]\.steps\[1\]\.tool: unknown tool 'grip' \(the robot driver has: gripper\)$"),
    ("unknown tool action", lambda d: steps(d)[1].update(action="squeeze"),
     r"^process\.operations\[0\]\.steps\[1\]\.action: unknown action 'squeeze' for tool gripper \(it has: open, "),
    ("unknown motion group", lambda d: steps(d)[0].update(group="legs"),
     r"^process\.operations\[0\]\.steps\[0\]\.group: unknown motion group 'legs'"),
    ("unknown pose table", lambda d: steps(d)[3].update(move_pose="parts"),
     r"^process\.operations\[0\]\.steps\[3\]\.move_pose: no pose table 'parts' \(the section has: part, pocket\)$"),
    ("duplicate operation name",
     lambda d: d["process"]["operations"][1].update(name=d["process"]["operations"][0]["name"]),
     r"^process\.operations\[1\]\.name: 'pick part' is used twice$"),
    ("unknown parameter", lambda d: steps(d)[2]["offset"][2].update(parameter="approach_hight"),
     r"^process\.operations\[0\]\.steps\[2\]\.offset\[2\]\.parameter: unknown parameter 'approach_hight'"),
    ("non-numeric parameter in a step", lambda d: steps(d)[2]["offset"][2].update(parameter="recipe_name"),
     r"^process\.operations\[0\]\.steps\[2\]\.offset\[2\]: parameter 'recipe_name' is not a number"),
    ("parameter default above its max", lambda d: _set_param(d, default=500),
     r"^parameters\.items\[0\]\.default: .*200"),
    ("parameter default with too many decimals", lambda d: _set_param(d, default=100.25),
     r"^parameters\.items\[0\]\.default: "),
    ("enum default not an option", lambda d: items(d)[2].update(default="glue"),
     r"^parameters\.items\[2\]\.default: "),
    ("duplicate parameter id", lambda d: items(d)[1].update(id="approach_height"),
     r"^parameters\.items\[1\]\.id: 'approach_height' is already the id of items\[0\]$"),
    ("parameter min above max", lambda d: _set_param(d, min=300),
     r"^parameters\.items\[0\]\.min: 300\.?0? is above max 200"),
    ("joint that is not a UR joint", lambda d: d["manual"]["groups"][0]["joints"].__setitem__(2, "elbow"),
     r"^manual\.groups\[0\]\.joints\[2\]: 'elbow' is not a joint of the robot \(a joint name ends with one of "
     r"shoulder_pan_joint, "),
    ("the same robot joint twice in a group",
     lambda d: d["manual"]["groups"][0]["joints"].__setitem__(2, "x_wrist_3_joint"),
     r"^manual\.groups\[0\]\.joints\[5\]: 'wrist_3_joint' is the same robot joint \(wrist_3_joint\) as joints\[2\]$"),
    ("a tool on a group the cell does not have", lambda d: d["manual"]["tools"][0].update(group="legs"),
     r"^manual\.tools\[0\]\.group: 'legs' is not a motion group \(manual\.groups: arm\)$"),
    ("a host that is no host", lambda d: d["manual"]["groups"][0].update(host="ur 5"),
     r"^manual\.groups\[0\]\.host: expected a host name or an IPv4 address, got 'ur 5'$"),
    ("two arms publishing the same joint names",
     lambda d: d["manual"]["groups"].append({"name": "other", "host": "127.0.2.9", "joints": ["elbow_joint"]}),
     r"^manual\.groups\[1\]: joint name 'elbow_joint' is also a joint of the arm at 127\.0\.0\.1 \(group arm\)"),
    ("a tool step naming another group than its tool's",
     lambda d: (d["manual"]["groups"].append({"name": "wrist", "joints": ["wrist_3_joint"]}),
                steps(d)[1].update(group="wrist")),
     r"^process\.operations\[0\]\.steps\[1\]\.group: tool gripper is on group arm \(manual\.tools\), not wrist$"),
    ("a start configuration of an unknown group", lambda d: d["process"].update(start_configuration={"legs": "home"}),
     r"^process\.start_configuration\.legs: unknown motion group 'legs'"),
    ("a start configuration a group does not have",
     lambda d: d["process"].update(start_configuration={"arm": "nowhere"}),
     r"^process\.start_configuration\.arm: unknown configuration 'nowhere' for group arm"),
    ("configuration with the wrong number of values",
     lambda d: d["manual"]["groups"][0]["configurations"].update(home=[0, 0, 0, 0, 0]),
     r"^manual\.groups\[0\]\.configurations\.home: 5 values for 6 joints$"),
    ("duplicate module name", lambda d: d["modules"][1].update(name="Simulated cell"),
     r"^modules\[1\]\.name: duplicate module name 'Simulated cell'$"),
    ("force_clear_n above force_limit_n", lambda d: d["alarms"].update(force_clear_n=90),
     r"^alarms\.force_clear_n: must not be above force_limit_n \(80\), got 90$"),
    ("unknown sim camera view", lambda d: d["video"]["streams"][0].update(view="top"),
     r"^video\.streams\[0\]\.view: unknown viewpoint 'top' \(the sim has: workbench, global\)$"),
    ("two streams on one topic", lambda d: d["video"]["streams"][1].update(topic=d["video"]["streams"][0]["topic"]),
     r"^video\.streams\[1\]\.topic: .* is already another stream's topic$"),
]


@pytest.mark.parametrize("name,mutate,expected", MISTAKES, ids=[m[0] for m in MISTAKES])
def test_each_mistake_is_one_line_naming_the_field(name: str, mutate: Callable[[dict], None], expected: str) -> None:
    d = demo()
    mutate(d)
    report = check_cell(d, "x.yaml")
    assert len(report.problems) == 1, report.problems
    assert re.search(expected, report.problems[0]), report.problems[0]


def test_all_sections_are_checked_in_one_run(tmp_path: Path, capsys) -> None:
    d = demo()
    steps(d)[0]["move_named"] = "hom"
    d["modules"][1]["name"] = "Simulated cell"
    d["alarms"]["force_clear_n"] = 90
    d["manual"]["groups"][0]["joints"][2] = "elbow"
    f = tmp_path / "cell.yaml"
    f.write_text(yaml.safe_dump(d), encoding="utf-8")
    assert main([str(f)]) == EXIT_PROBLEMS
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0] for line in lines] == [
        "manual.groups[0].joints[2]", "process.operations[0].steps[0].move_named", "alarms.force_clear_n",
        "modules[1].name"], lines


def test_a_bad_parameters_section_does_not_hide_the_process_checks() -> None:
    d = demo()
    items(d)[0]["default"] = 500          # the parameters node refuses the section ...
    steps(d)[0]["move_named"] = "hom"     # ... and the process has a mistake of its own
    problems = check_cell(d).problems
    assert [p.split(":")[0] for p in problems] == ["parameters.items[0].default",
                                                  "process.operations[0].steps[0].move_named"], problems


def test_sections_the_cell_does_not_have_are_not_checked() -> None:
    d = demo()
    for section in ("manual", "parameters", "process", "alarms", "modules", "routines", "video"):
        d.pop(section)
    assert check_cell(d).problems == []


def test_what_a_node_only_logs_is_a_warning(capsys, tmp_path: Path) -> None:
    d = demo()
    d["routines"]["groups"] = ["arm", "legs"]
    d["operation_mode"]["modes"].remove("alarm")
    f = tmp_path / "cell.yaml"
    f.write_text(yaml.safe_dump(d), encoding="utf-8")
    assert main([str(f)]) == EXIT_OK
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("warning: alarms.alarm_mode: operation_mode.modes has no 'alarm'"), out
    assert out[1].startswith("warning: routines.groups[1]: 'legs' is not a motion group"), out
    d["alarms"]["alarm_mode"] = ""   # switched off on purpose: nothing to say
    d["routines"]["groups"] = ["arm"]
    assert check_cell(d).warnings == []


def test_a_parser_that_crashes_is_reported_too() -> None:
    d = demo()
    d["manual"]["groups"][0]["configurations"] = [[0, 0]]   # the schema refuses it; the driver would die of it
    problems = check_cell(d).problems
    assert any(p.startswith("manual: the robot driver cannot read this section (AttributeError") for p in problems), \
        problems


def test_hosts_come_from_the_environment_the_check_runs_in() -> None:
    """UR_HOSTS and UR_HOST are read as the driver reads them: a UR_HOSTS naming a group the cell lacks, or two
    groups whose joint names differ on one arm, is a problem here too."""
    d = demo()
    d["manual"]["groups"].append({"name": "right", "host": "127.0.2.2", "joints": [
        "right_shoulder_pan_joint", "right_shoulder_lift_joint", "right_elbow_joint", "right_wrist_1_joint",
        "right_wrist_2_joint", "right_wrist_3_joint"], "configurations": {"home": [0, -1.57, 1.57, -1.57, -1.57, 0]}})
    assert check_cell(d).problems == []
    report = Report()
    check_manual(d, report, {"UR_HOSTS": "legs=127.0.3.1"})
    assert report.problems == ["UR_HOSTS: 'legs' is not a motion group of this cell (manual.groups: arm, right)"]
    report = Report()
    check_manual(d, report, {"UR_HOSTS": "right=127.0.0.1"})  # both groups on one arm: the joints disagree
    assert len(report.problems) == 1 and report.problems[0].startswith(
        "manual.groups[1].joints[0]: 'right_shoulder_pan_joint' is robot joint shoulder_pan_joint of the arm at "
        "127.0.0.1, which group arm calls 'shoulder_pan_joint'"), report.problems
    report = Report()
    check_manual(d, report, {"UR_HOST": "ur5.local", "UR_HOSTS": " right = 10.0.0.7 "})
    assert report.problems == []


def test_an_unknown_initial_mode() -> None:
    d = demo()
    d["operation_mode"]["initial"] = "dancing"
    assert check_cell(d).problems == ["operation_mode: initial mode 'dancing' is not one of "
                                      "['idle', 'running', 'paused', 'alarm', 'programming', 'manual']"]


@pytest.mark.parametrize("content,expected", [
    (None, r": cannot read: No such file"),
    ("cell: [unclosed\n", r": not valid YAML: "),
    ("- just\n- a list\n", r": not a cell file$"),
    (b"\xff\xfe bad utf-8", r": cannot read: "),
])
def test_an_unreadable_file_exits_with_2(tmp_path: Path, capsys, content: Any, expected: str) -> None:
    f = tmp_path / "cell.yaml"
    if isinstance(content, bytes):
        f.write_bytes(content)
    elif content is not None:
        f.write_text(content, encoding="utf-8")
    assert main([str(f)]) == EXIT_UNREADABLE
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 1 and out[0].startswith(str(f)) and re.search(expected, out[0]), out


def test_usage(capsys) -> None:
    assert main(["a.yaml", "b.yaml"]) == EXIT_UNREADABLE
    assert "usage:" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------- ros_control groups
IIWA = Path(__file__).resolve().parents[4] / "config" / "iiwa-cell.yaml"
_IIWA_DOC = yaml.safe_load(IIWA.read_text(encoding="utf-8"))


def iiwa() -> dict[str, Any]:
    return copy.deepcopy(_IIWA_DOC)


def iiwa_urdf(with_tip: bool) -> str:
    """The arm as a URDF file of the robot PC: the model the sim drives, renamed; with or without the TCP link."""
    import pybullet_data
    text = (Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf").read_text().replace("lbr_iiwa_", "iiwa_")
    if not with_tip:
        return text
    return text.replace("</robot>", '<link name="iiwa_link_ee"/><joint name="iiwa_joint_ee" type="fixed">'
                                    '<parent link="iiwa_link_7"/><child link="iiwa_link_ee"/>'
                                    '<origin xyz="0 0 0.06"/></joint></robot>')


def test_the_iiwa_cell_passes(capsys) -> None:
    report = check_cell(iiwa(), str(IIWA))
    assert (report.problems, report.warnings) == ([], [])
    assert main([str(IIWA)]) == EXIT_OK
    assert capsys.readouterr().out == ""


def test_a_urdf_file_without_the_tip_link(tmp_path: Path) -> None:
    """A group reading its URDF from a file (relative to the cell file) is checked against that file."""
    d = iiwa()
    rc = d["manual"]["groups"][0]["ros_control"]
    del rc["robot_description"]
    rc["urdf"] = "urdf/iiwa.urdf"
    (tmp_path / "urdf").mkdir()
    urdf = tmp_path / "urdf" / "iiwa.urdf"
    urdf.write_text(iiwa_urdf(with_tip=False), encoding="utf-8")
    problems = check_cell(d, str(tmp_path / "cell.yaml")).problems
    assert len(problems) == 1, problems
    assert problems[0].startswith("manual.groups[0].ros_control: the URDF (urdf/iiwa.urdf) does not give the arm's "
                                  "kinematics: tip link 'iiwa_link_ee' is not in the robot description (links: "
                                  "iiwa_link_0, "), problems
    urdf.write_text(iiwa_urdf(with_tip=True), encoding="utf-8")
    assert check_cell(d, str(tmp_path / "cell.yaml")).problems == []
    urdf.unlink()
    problems = check_cell(d, str(tmp_path / "cell.yaml")).problems
    assert problems == [f"manual.groups[0].ros_control.urdf: cannot read {urdf}: No such file or directory"], problems


def test_a_configuration_outside_a_joint_limit() -> None:
    """Checked against the simulated driver's URDF when the cell is simulated; a real arm's robot_description
    parameter is only known when the driver connects."""
    d = iiwa()
    d["manual"]["groups"][0]["configurations"]["pick_approach"][3] = -2.2   # iiwa joint 4: +-2.094 rad
    assert check_cell(d, str(IIWA)).problems == [
        "manual.groups[0].configurations.pick_approach[3]: -2.2 rad is outside the limits of iiwa_joint_4 "
        "[-2.094, 2.094]"]
    d["robot"]["simulated"] = False
    assert check_cell(d, str(IIWA)).problems == []


@pytest.mark.parametrize("mutate,expected", [
    (lambda d: d["manual"]["groups"][0].update(host="127.0.0.1"),
     "manual.groups[0].host: a ros_control group has no controller host (its driver owns it)"),
    (lambda d: d["manual"]["groups"].append(dict(copy.deepcopy(d["manual"]["groups"][0]), name="arm2")),
     "manual.groups[1].ros_control.controller: /iiwa/PositionJointInterface_trajectory_controller moves another "
     "group already (one motion group per trajectory controller)"),
], ids=["host", "two groups on one controller"])
def test_what_the_driver_refuses_in_a_ros_control_group(mutate: Callable[[dict], None], expected: str) -> None:
    d = iiwa()
    mutate(d)
    assert check_cell(d, str(IIWA)).problems == [expected]
