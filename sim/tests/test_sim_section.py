"""The cell file's `simulation:` section (sim/cell_file.py parse_simulation), the WrenchStamped `group`, the host rule
(sim/hosts.py) and how the CLI gives every arm its address. No sim process here (except one CLI refusal)."""
from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from sim.__main__ import arm_hosts, parse_args
from sim.cell import Cell, CellOptions
from sim.cell_file import CellFileError, devices_from, load_devices, parse_simulation
from sim.hosts import parse_host_list, resolve_hosts
from sim.scene import DEFAULT_WORLD, ArmSpec, GripperSpec, PartsSpec, StationSpec, VacuumSpec
from sim.world import World

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "config" / "demo-cell.yaml"
TWIN = ROOT / "config" / "twin-arm-cell.yaml"
CELLS = Path(__file__).resolve().parent / "cells"
WRENCH = "geometry_msgs/WrenchStamped"


def twin_doc() -> dict:
    return yaml.safe_load(TWIN.read_text())


# ---------------------------------------------------------------------------------------------- defaults
def test_without_the_section_the_sim_builds_the_demo_world() -> None:
    assert load_devices(str(DEMO)).world == DEFAULT_WORLD
    assert load_devices(str(CELLS / "no-devices.yaml")).world == DEFAULT_WORLD
    w = DEFAULT_WORLD
    assert w.arms == (ArmSpec(group="arm", base=(0.0, 0.0, 0.0), yaw=0.0,
                              tool=GripperSpec(close_output=0, closed_input=1, part_input=2)),)
    assert w.parts == PartsSpec(size=0.04, mass=0.1, positions=None, count=3, start=(-0.45, -0.25), step=(0.0, 0.12),
                                jitter=(0.03, 0.02, 0.3))
    assert w.stations == (StationSpec(name="fixture", kind="fixture", position=(-0.35, 0.35), pockets=3),)
    assert w.views == ()
    # The demo's arm stands for the cell's first motion group.
    doc = {"manual": {"groups": [{"name": "cobot", "joints": []}, {"name": "other", "joints": []}]}}
    assert parse_simulation(doc).arms == (ArmSpec(group="cobot"),)


def test_an_empty_section_and_one_spelling_the_demo_out_give_the_demo_world() -> None:
    assert parse_simulation({"simulation": {}}) == DEFAULT_WORLD
    spelled = {"simulation": {
        "arms": [{"group": "arm", "base": [0, 0, 0, 0],
                  "tool": {"kind": "gripper", "close_output": 0, "closed_input": 1, "part_input": 2}}],
        "parts": {"size": 0.04, "mass": 0.1, "count": 3, "start": [-0.45, -0.25], "step": [0, 0.12],
                  "jitter": [0.03, 0.02, math.degrees(0.3)]},
        "stations": [{"name": "fixture", "kind": "fixture", "position": [-0.35, 0.35], "pockets": 3}]}}
    spec = parse_simulation(spelled)
    assert spec.arms == DEFAULT_WORLD.arms and spec.stations == DEFAULT_WORLD.stations
    assert spec.parts.jitter[2] == pytest.approx(0.3, abs=1e-15)
    a, b = World(seed=0), World(seed=0, spec=spec)
    try:
        for (pa, oa), (pb, ob) in zip(a.body_poses(), b.body_poses()):
            np.testing.assert_allclose(pa, pb, atol=1e-12)
            np.testing.assert_allclose(oa, ob, atol=1e-12)
        assert a.fixture_slots == b.fixture_slots == [(-0.35, 0.292), (-0.35, 0.35), (-0.35, 0.408)]
    finally:
        a.close()
        b.close()


# ---------------------------------------------------------------------------------------------- the twin cell
def test_twin_cell_section() -> None:
    d = load_devices(str(TWIN))
    w = d.world
    left, right = w.arms
    assert (left.group, left.base, left.yaw) == ("left", (-0.48, 0.0, 0.0), pytest.approx(math.pi))
    assert left.tool == GripperSpec(close_output=0, closed_input=1, part_input=2)
    assert (right.group, right.base, right.yaw) == ("right", (0.48, 0.0, 0.0), 0.0)
    assert right.tool == VacuumSpec(suction_output=4, vacuum_input=5)
    assert 0.9 <= math.dist(left.base, right.base) <= 1.0
    assert w.parts.positions == ((-0.15, -0.40, 0.0), (-0.15, -0.28, 0.0), (-0.15, -0.16, 0.0))
    assert [s.kind for s in w.stations] == ["stand", "fixture"]
    assert [v.name for v in w.views] == ["hand_over", "overview"]
    assert d.all_views == ["workbench", "global", "hand_over", "overview"]
    # The tools of manual.tools and the IO of simulation.arms agree.
    doc = twin_doc()
    tools = {t["name"]: t for t in doc["manual"]["tools"]}
    assert tools["gripper"]["group"] == "left" and tools["vacuum"]["group"] == "right"
    close = next(a for a in tools["gripper"]["actions"] if a["name"] == "close")["steps"]
    assert close[0]["digital_out"] == left.tool.close_output and close[1]["wait_input"] == left.tool.closed_input
    on = next(a for a in tools["vacuum"]["actions"] if a["name"] == "on")["steps"]
    assert on[0]["digital_out"] == right.tool.suction_output and on[1]["wait_input"] == right.tool.vacuum_input
    # Streams may show the cell's own viewpoints; unnamed streams cycle through all of them.
    doc["video"] = {"streams": [{"name": "a", "topic": "/a", "view": "hand_over"}, {"name": "b", "topic": "/b"},
                                {"name": "c", "topic": "/c"}, {"name": "d", "topic": "/d"}]}
    d = devices_from(doc, "twin.yaml")
    assert [s.view for s in d.streams] == ["hand_over", "global", "hand_over", "overview"]
    assert d.views == ["global", "hand_over", "overview"]


def test_twin_world_builds_both_arms_in_one_world() -> None:
    w = World(seed=0, spec=load_devices(str(TWIN)).world)
    try:
        assert [a.tool for a in w.arms] == ["gripper", "vacuum"]
        assert len({a.robot for a in w.arms}) == 2
        assert [p for p, _ in w.body_poses()] == [(-0.15, -0.40, 0.02), (-0.15, -0.28, 0.02), (-0.15, -0.16, 0.02)]
        assert w.pockets["output"] == [(0.15, 0.25), (0.15, 0.33), (0.15, 0.41)]
        top = w.p.getAABB(w.stations["hand_over"])[1][2]
        assert top == pytest.approx(0.08, abs=1e-3)
        # A replica (the camera process) follows a snapshot of both arms.
        for a in w.arms:
            for j in a.arm_joints:
                w.p.resetJointState(a.robot, j, 0.1 * j)
        replica = World(seed=0, spec=w.spec, render_only=True)
        try:
            replica.apply_snapshot(w.snapshot())
            assert replica.snapshot() == w.snapshot()
        finally:
            replica.close()
    finally:
        w.close()


# ---------------------------------------------------------------------------------------------- errors
ARM = {"group": "a", "base": [0, 0, 0, 0], "tool": {"kind": "gripper"}}


@pytest.mark.parametrize("section, where", [
    (["x"], "simulation: expected a mapping"),
    ({"robots": []}, "simulation.robots: unknown field"),
    ({"arms": []}, "simulation.arms: expected a list of at least one arm"),
    ({"arms": [{"base": [0, 0, 0, 0]}]}, "simulation.arms[0].group: expected the name of a motion group"),
    ({"arms": [dict(ARM, group="nope")]}, "simulation.arms[0].group: 'nope' is not a motion group of manual.groups"),
    ({"arms": [ARM, dict(ARM, base=[1, 0, 0, 0])]}, "simulation.arms[1].group: 'a' is already another arm's group"),
    ({"arms": [ARM, dict(ARM, group="b", base=[0.1, 0, 0, 0])]}, "simulation.arms[1].base: 0.10 m from the base"),
    ({"arms": [dict(ARM, base=[0, 0, 0])]}, "simulation.arms[0].base: expected [x, y, z, yaw_deg]"),
    ({"arms": [dict(ARM, base=[0, 0, 0, "east"])]}, "simulation.arms[0].base[3]: expected a number"),
    ({"arms": [dict(ARM, tool={"kind": "magnet"})]}, "simulation.arms[0].tool.kind: expected gripper or vacuum"),
    ({"arms": [dict(ARM, tool={"kind": "gripper", "suction_output": 1})]},
     "simulation.arms[0].tool.suction_output: unknown field"),
    ({"arms": [dict(ARM, tool={"kind": "vacuum", "suction_output": 8})]},
     "simulation.arms[0].tool.suction_output: expected an integer from 0 to 7"),
    ({"arms": [dict(ARM, tool={"kind": "vacuum", "vacuum_input": 0})]},
     "simulation.arms[0].tool.vacuum_input: expected an integer from 1 to 7"),
    ({"arms": [dict(ARM, tool={"kind": "gripper", "closed_input": 2})]},
     "simulation.arms[0].tool.part_input: DI2 is already the closed_input"),
    ({"arms": [dict(ARM, start_joints=[0, 0, 0])]}, "simulation.arms[0].start_joints: expected 6 joint positions"),
    ({"parts": {"size": 0.5}}, "simulation.parts.size: expected a number from 0.01 to 0.1"),
    ({"parts": {"positions": [[0, 0]], "count": 1}}, "simulation.parts.count: give either positions or count"),
    ({"parts": {"positions": [[0, 0, 0, 0]]}}, "simulation.parts.positions[0]: expected [x, y] or [x, y, yaw_deg]"),
    ({"parts": {"count": 30}}, "simulation.parts.count: expected an integer from 0 to 20"),
    ({"parts": {"jitter": [0.01, -0.01, 0]}}, "simulation.parts.jitter[1]: expected a number >= 0"),
    ({"stations": {"a": 1}}, "simulation.stations: expected a list"),
    ({"stations": [{"name": "s", "kind": "table"}]}, "simulation.stations[0].kind: expected stand or fixture"),
    ({"stations": [{"name": "s", "kind": "stand"}]}, "simulation.stations[0].position: required"),
    ({"stations": [{"name": "S", "kind": "stand", "position": [0, 0]}]}, "simulation.stations[0].name"),
    ({"stations": [{"name": "s", "kind": "stand", "position": [0, 0], "pockets": 2}]},
     "simulation.stations[0].pockets: unknown field"),
    ({"stations": [{"name": "s", "kind": "stand", "position": [0, 0]}, {"name": "s", "kind": "stand",
                                                                         "position": [0, 0.5]}]},
     "simulation.stations[1].name: 's' is already"),
    ({"stations": [{"name": "f", "kind": "fixture", "pockets": [[0, 0], [0, 0.05]]}]},
     "simulation.stations[0].pockets[1]: overlaps pockets[0]"),
    ({"stations": [{"name": "f", "kind": "fixture", "position": [0, 0], "pockets": [[0, 0]]}]},
     "simulation.stations[0].position: a fixture with a list of pockets"),
    ({"stations": [{"name": "f", "kind": "fixture", "position": [0, 0], "pockets": 0}]},
     "simulation.stations[0].pockets: expected an integer from 1 to 10"),
    ({"stations": [{"name": "s", "kind": "stand", "position": [0, 0], "height": 2}]},
     "simulation.stations[0].height: expected a number from 0.01 to 0.5"),
    ({"views": [{"eye": [0, 0, 1]}]}, "simulation.views: expected a mapping"),
    ({"views": {"global": {"eye": [1, 1, 1], "target": [0, 0, 0]}}}, "simulation.views.global: 'global' is a built-in"),
    ({"views": {"top": {"eye": [1, 1, 1]}}}, "simulation.views.top.target: required"),
    ({"views": {"top": {"eye": [1, 1], "target": [0, 0, 0]}}}, "simulation.views.top.eye: expected [x, y, z]"),
    ({"views": {"top": {"eye": [1, 1, 1], "target": [0, 0, 0], "fov": 170}}}, "simulation.views.top.fov"),
    ({"views": {"top": {"eye": [1, 1, 1], "target": [0, 0, 0], "zoom": 2}}}, "simulation.views.top.zoom: unknown"),
])
def test_errors_name_the_field(section, where) -> None:
    doc = {"manual": {"groups": [{"name": "a", "joints": []}, {"name": "b", "joints": []}]}, "simulation": section}
    with pytest.raises(CellFileError) as e:
        devices_from(doc, "x.yaml")
    assert str(e.value).startswith("cell file x.yaml: ") and where in str(e.value), str(e.value)


def test_arms_without_a_manual_section_may_name_any_group() -> None:
    spec = parse_simulation({"simulation": {"arms": [ARM, dict(ARM, group="b", base=[1, 0, 0, 90],
                                                              tool={"kind": "vacuum"})]}})
    assert [a.group for a in spec.arms] == ["a", "b"]
    assert spec.arms[1].yaw == pytest.approx(math.pi / 2)
    assert spec.arms[1].tool == VacuumSpec(suction_output=0, vacuum_input=1)


# ---------------------------------------------------------------------------------------------- sensors per arm
def test_wrench_sensors_name_their_arm_default_the_first() -> None:
    doc = twin_doc()
    doc["sensors"] = [{"title": "l", "kind": "time-series", "topic": "/l/wrench", "type": WRENCH},
                      {"title": "r", "kind": "time-series", "topic": "/r/wrench", "type": WRENCH, "group": "right"},
                      {"title": "r2", "kind": "time-series", "topic": "/r/wrench", "type": WRENCH, "group": "right"},
                      {"title": "t", "kind": "scatter", "topic": "/l/tactile", "type": "cell_msgs/Scatter"}]
    d = devices_from(doc)
    assert d.wrench_topics == ("/l/wrench", "/r/wrench") and d.wrench_groups == ("left", "right")
    assert d.tactile_topics == ("/l/tactile",) and d.tactile_group == "left"
    assert load_devices(str(DEMO)).wrench_groups == ("arm",)


@pytest.mark.parametrize("sensors, where", [
    ([{"topic": "/w", "type": WRENCH, "group": "middle"}], "sensors[0].group: no simulated arm 'middle'"),
    ([{"topic": "/w", "type": WRENCH}, {"topic": "/w", "type": WRENCH, "group": "right"}],
     "sensors[1].group: /w already carries the wrist F/T of arm 'left'"),
])
def test_wrench_group_errors(sensors, where) -> None:
    doc = twin_doc()
    doc["sensors"] = sensors
    with pytest.raises(CellFileError, match=re.escape(where)):
        devices_from(doc)


def test_tactile_pad_needs_a_gripper_arm() -> None:
    doc = {"simulation": {"arms": [dict(ARM, tool={"kind": "vacuum"})]},
           "sensors": [{"topic": "/t", "type": "cell_msgs/Scatter"}]}
    with pytest.raises(CellFileError, match=r"sensors\[0\]: a tactile pad needs an arm with a gripper"):
        devices_from(doc)


# ---------------------------------------------------------------------------------------------- hosts
@pytest.mark.parametrize("section, env, expected", [
    (None, {}, {}),
    ({"groups": [{"name": "arm"}]}, {}, {"arm": "127.0.0.1"}),
    ({"groups": [{"name": "arm"}]}, {"UR_HOST": "10.0.0.5"}, {"arm": "10.0.0.5"}),
    ({"groups": [{"name": "arm"}]}, {"UR_HOST": "  "}, {"arm": "127.0.0.1"}),
    ({"groups": [{"name": "l", "host": "127.0.2.1"}, {"name": "r", "host": "127.0.2.2"}, {"name": "x"}]},
     {"UR_HOST": "10.0.0.5"}, {"l": "127.0.2.1", "r": "127.0.2.2", "x": "10.0.0.5"}),
    ({"groups": [{"name": "l", "host": "127.0.2.1"}, {"name": "r", "host": "127.0.2.2"}]},
     {"UR_HOSTS": " r=127.0.3.9 , ,other=1.2.3.4", "UR_HOST": "10.0.0.5"}, {"l": "127.0.2.1", "r": "127.0.3.9"}),
    ({"groups": [{"name": "l", "host": " "}, "junk", {"host": "1.1.1.1"}]}, {}, {"l": "127.0.0.1"}),
])
def test_resolve_hosts(section, env, expected) -> None:
    assert resolve_hosts(section, env) == expected


@pytest.mark.parametrize("text", ["left", "=127.0.0.1", "left=", "a=1,b"])
def test_host_list_entries_must_be_group_equals_host(text) -> None:
    with pytest.raises(ValueError, match="UR_HOSTS: .* is not <group>=<host>"):
        parse_host_list(text)


def test_each_arm_gets_its_groups_host() -> None:
    doc = twin_doc()
    d = devices_from(doc)
    assert arm_hosts(doc, d, {}) == {"left": "127.0.2.1", "right": "127.0.2.2"}
    assert arm_hosts(doc, d, {"UR_HOSTS": "right=127.0.3.7"}) == {"left": "127.0.2.1", "right": "127.0.3.7"}
    assert arm_hosts(doc, d, {"UR_HOSTS": "right=127.0.3.7"}, hosts="right=127.0.3.8,left=127.0.3.9") == \
        {"left": "127.0.3.9", "right": "127.0.3.8"}
    # --host stands in for UR_HOST with several arms: only groups without their own host take it.
    del doc["manual"]["groups"][1]["host"]
    assert arm_hosts(doc, devices_from(doc), {}, host="127.0.3.3") == {"left": "127.0.2.1", "right": "127.0.3.3"}
    with pytest.raises(ValueError, match="arms left and right both on 127.0.2.1"):
        arm_hosts(doc, devices_from(doc), {"UR_HOST": "127.0.2.1"})
    with pytest.raises(ValueError, match="--hosts: no simulated arm 'middle'"):
        arm_hosts(doc, d, {}, hosts="middle=127.0.3.1")
    # A motion group that is no simulated arm (a second group of one arm, say) is ignored, as in UR_HOSTS.
    doc["manual"]["groups"].append({"name": "left_tool", "joints": ["left_wrist_3_joint"], "host": "127.0.2.1"})
    assert arm_hosts(doc, devices_from(doc), {}, host="127.0.3.3", hosts="left_tool=127.0.2.1,right=127.0.3.4") == \
        {"left": "127.0.2.1", "right": "127.0.3.4"}
    # One arm: --host is its address whatever the file says (as before the section existed).
    demo = yaml.safe_load(DEMO.read_text())
    demo["manual"]["groups"][0]["host"] = "127.0.2.9"
    dd = devices_from(demo)
    assert arm_hosts(demo, dd, {"UR_HOST": "1.1.1.1"}, host="127.0.0.7") == {"arm": "127.0.0.7"}
    assert arm_hosts(demo, dd, {"UR_HOST": "1.1.1.1"}) == {"arm": "127.0.2.9"}
    assert arm_hosts(demo, dd, {}, host="127.0.0.7", hosts="arm=127.0.0.8") == {"arm": "127.0.0.8"}


def test_cli_options_give_the_hosts(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("UR_HOSTS", raising=False)
    monkeypatch.delenv("UR_HOST", raising=False)
    monkeypatch.delenv("CELL_CONFIG", raising=False)
    assert parse_args([]).hosts == {"arm": "127.0.0.1"}
    assert parse_args(["--host", "127.0.0.9"]).hosts == {"arm": "127.0.0.9"}
    monkeypatch.setenv("UR_HOSTS", "left=127.0.3.5")
    assert parse_args(["--cell", str(TWIN)]).hosts == {"left": "127.0.3.5", "right": "127.0.2.2"}


@pytest.mark.parametrize("env, args, expected", [
    ({"UR_HOSTS": "left"}, [], 'UR_HOSTS: "left" is not <group>=<host>'),
    ({}, ["--hosts", "left=127.0.3.1,right=127.0.3.1"], "arms left and right both on 127.0.3.1"),
])
def test_cli_refuses_bad_hosts_in_one_line(env, args, expected) -> None:
    run_env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(ROOT), "ROS_MASTER_URI": "http://127.0.0.1:1", **env}
    r = subprocess.run([sys.executable, "-m", "sim", "--no-ros", "--cell", str(TWIN), *args], cwd=ROOT, env=run_env,
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and expected in r.stderr and "Traceback" not in r.stderr, r.stderr


# ---------------------------------------------------------------------------------------------- faults per arm
def test_faults_per_arm_and_the_cells_door() -> None:
    d = load_devices(str(TWIN))
    cell = Cell(CellOptions(devices=d, hosts={"left": "127.0.3.19", "right": "127.0.3.20"}, ros=False,
                            cameras=False))  # not started: no port is opened
    try:
        ids = [f.id for f in cell.faults.snapshot()]
        assert ids == ["left.protective_stop", "left.gripper_fault", "left.force_limit", "right.protective_stop",
                       "right.vacuum_fault", "right.force_limit", "door_open"]
        texts = {f.id: f.text for f in cell.faults.snapshot()}
        assert texts["right.vacuum_fault"].startswith("Robot right: Vacuum fault")
        left, right = cell.controllers["left"], cell.controllers["right"]
        assert cell.trigger_fault("right.protective_stop") == (True, "protective_stop done")
        assert (left.safety_mode, right.safety_mode) == (1, 3)
        active = {f.id for f in cell.faults.snapshot() if f.active}
        assert active == {"right.protective_stop"}
        assert cell.trigger_fault("door_open")[0]
        assert left.safety_mode == 5 and left.door_open and right.door_open
        ok, msg = cell.trigger_fault("left.vacuum_fault")
        assert not ok and "gripper_fault" in msg
        assert cell.trigger_fault("vacuum_fault")[0] and cell.faults.faults["right.vacuum_fault"].active
        ok, msg = cell.trigger_fault("middle.reset")
        assert not ok and "unknown arm 'middle'" in msg
        assert cell.trigger_fault("reset")[0]
        assert (left.safety_mode, right.safety_mode) == (1, 1)
        assert not any(f.active for f in cell.faults.snapshot())
        ok, msg = cell.trigger_fault("meltdown")
        assert not ok and "<group>.<fault>" in msg
    finally:
        cell.world.close()


def test_one_arm_keeps_the_demos_fault_ids() -> None:
    cell = Cell(CellOptions(devices=load_devices(str(DEMO)), ros=False, cameras=False))
    try:
        assert [f.id for f in cell.faults.snapshot()] == ["protective_stop", "gripper_fault", "door_open",
                                                          "force_limit"]
        ok, msg = cell.trigger_fault("nope")
        assert not ok and msg == "unknown fault 'nope' (protective_stop, gripper_fault, door_open, force_limit, reset)"
    finally:
        cell.world.close()
