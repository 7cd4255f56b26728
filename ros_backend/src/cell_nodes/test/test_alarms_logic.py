"""Alarms, the plain-Python logic (no ROS): each source's aggregation, active -> inactive -> reset -> gone, reset
keeps active ones, first/last seen, the overall status, the operation-mode decision, the cell file section.
Messages are fed as plain dicts; timestamps are explicit seconds."""
from __future__ import annotations

import re
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml

from cell_nodes.alarms.config import AlarmsConfig, ConfigError, alarm_mode_problem, parse_alarms
from cell_nodes.alarms.core import Alarms
from cell_nodes.alarms.mode import ModeKeeper, ModeRequest
from cell_nodes.alarms.table import ERROR, INFO, WARNING, AlarmTable, Condition

DEMO = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"
MODE = {"topic": "/cell/mode", "set_service": "/cell/set_mode", "modes": ["idle", "running", "alarm", "manual"]}
WRENCH = "/cell/wrench"


def cell(**alarms) -> dict:
    return {"operation_mode": MODE, "alarms": alarms,
            "sensors": [{"title": "F/T", "kind": "time-series", "topic": WRENCH, "type": "geometry_msgs/WrenchStamped"},
                        {"title": "Tactile", "kind": "scatter", "topic": "/cell/tactile", "type": "cell_msgs/Scatter"}]}


def make(now: float = 100.0, **alarms) -> Alarms:
    return Alarms(parse_alarms(cell(**{"force_limit_n": 80, **alarms})), now)


def robot(connected: bool = True, safety: str = "NORMAL", mode: str = "RUNNING", host: str = "10.0.0.5") -> dict:
    return {"connected": connected, "controller": host, "safety_mode": safety, "robot_mode": mode}


def fault(fid: str, active: bool, since: float = 0.0, severity: int = ERROR) -> dict:
    return {"id": fid, "text": f"{fid} text", "severity": severity, "active": active, "since": since}


def wrench(fx: float = 0.0, fy: float = 0.0, fz: float = -10.0) -> dict:
    return {"wrench": {"force": {"x": fx, "y": fy, "z": fz}, "torque": {"x": 0, "y": 0, "z": 0}}}


def listed(a: Alarms) -> dict[str, bool]:
    return {x.id: x.active for x in a.alarms()}


# ---------------------------------------------------------------------------------------------- the table
def test_table_lifecycle_active_inactive_reset_gone_with_first_and_last_seen() -> None:
    t = AlarmTable()
    door = Condition("device.door_open", "door open", ERROR, "device")
    assert t.report("faults", [door], 10.0) is True
    a = t.get("device.door_open")
    assert (a.active, a.first_seen, a.last_seen, a.count) == (True, 10.0, 10.0, 1)
    assert t.report("faults", [door], 11.0) is False          # the same again: nothing to publish
    t.touch(12.5)                                              # still reported: seen at 12.5
    assert t.get("device.door_open").last_seen == 12.5
    assert t.report("faults", [], 14.0) is True                # gone: inactive, stays in the list
    a = t.get("device.door_open")
    assert (a.active, a.first_seen, a.last_seen) == (False, 10.0, 14.0)
    t.touch(20.0)                                              # an inactive alarm is not seen any more
    assert t.get("device.door_open").last_seen == 14.0
    assert t.report("faults", [door], 15.0) is True            # back before a reset: same entry, counted
    a = t.get("device.door_open")
    assert (a.active, a.first_seen, a.last_seen, a.count) == (True, 10.0, 15.0, 2)
    t.report("faults", [], 16.0)
    removed, active = t.reset()
    assert [x.id for x in removed] == ["device.door_open"] and active == []
    assert t.alarms() == []
    t.report("faults", [door], 30.0)                           # after the reset: a new entry
    assert (t.get("device.door_open").first_seen, t.get("device.door_open").count) == (30.0, 1)


def test_table_merges_sources_and_orders_the_list() -> None:
    t = AlarmTable()
    t.report("a", [Condition("x", "x from a", WARNING, "a")], 1.0)
    t.report("b", [Condition("x", "x from b", ERROR, "b"), Condition("info", "i", INFO, "b")], 2.0)
    assert t.get("x").severity == ERROR and t.get("x").text == "x from b"  # the more severe report wins
    t.report("b", [Condition("info", "i", INFO, "b")], 3.0)
    assert t.get("x").active and t.get("x").severity == WARNING          # still detected by source a
    t.report("a", [], 4.0)
    assert not t.get("x").active
    t.report("c", [Condition("w", "w", WARNING, "c"), Condition("e", "e", ERROR, "c")], 5.0)
    t.report("c", [Condition("w", "w", WARNING, "c"), Condition("e", "e", ERROR, "c"),
                   Condition("e2", "e2", ERROR, "c")], 6.0)
    # active first, most severe first, newest first; inactive last
    assert [(a.id, a.active) for a in t.alarms()] == [("e2", True), ("e", True), ("w", True), ("info", True),
                                                      ("x", False)]


def test_a_device_stamp_is_the_first_seen_time_but_never_in_the_future() -> None:
    t = AlarmTable()
    t.report("d", [Condition("old", "o", ERROR, "d", since=5.0), Condition("future", "f", ERROR, "d", since=99.0),
                   Condition("unset", "u", ERROR, "d", since=0.0)], 10.0)
    assert [t.get(i).first_seen for i in ("old", "future", "unset")] == [5.0, 10.0, 10.0]


# ---------------------------------------------------------------------------------------------- sources
@pytest.mark.parametrize("state, alarm_id, severity", [
    (robot(safety="PROTECTIVE_STOP"), "robot.arm.protective_stop", ERROR),
    (robot(safety="SYSTEM_EMERGENCY_STOP"), "robot.arm.emergency_stop", ERROR),
    (robot(safety="ROBOT_EMERGENCY_STOP"), "robot.arm.emergency_stop", ERROR),
    (robot(safety="SAFEGUARD_STOP"), "robot.arm.safeguard_stop", ERROR),
    (robot(safety="REDUCED"), "robot.arm.reduced_mode", WARNING),
    (robot(safety="VIOLATION"), "robot.arm.safety_violation", ERROR),
    (robot(safety="FAULT"), "robot.arm.safety_fault", ERROR),
    (robot(safety="UNDEFINED_SAFETY_MODE"), "robot.arm.safety_mode", WARNING),
    (robot(mode="POWER_OFF"), "robot.arm.power_off", INFO),
    (robot(connected=False, safety="", mode="NO_CONTROLLER"), "robot.arm.disconnected", ERROR),
])
def test_robot_state_becomes_alarms(state: dict, alarm_id: str, severity: int) -> None:
    a = make(now=0.0)
    assert not a.on_robot_state("arm", robot(), 0.5)
    assert a.on_robot_state("arm", state, 1.0)
    (alarm,) = a.alarms()
    assert (alarm.id, alarm.severity, alarm.active, alarm.source) == (alarm_id, severity, True, "robot")
    assert a.on_robot_state("arm", robot(), 2.0)
    assert listed(a) == {alarm_id: False}


def test_robot_normal_running_is_no_alarm_and_disconnected_names_the_host() -> None:
    a = make(now=0.0)
    assert not a.on_robot_state("arm", robot(), 1.0) and a.alarms() == []
    a.on_robot_state("arm", robot(connected=False, safety="", mode="NO_CONTROLLER", host="10.0.0.5"), 2.0)
    assert a.alarms()[0].text == "Robot arm: robot controller at 10.0.0.5 is unreachable"
    st = a.status()
    assert (st.controller_connected, st.safety_mode, st.status) == (False, "", "fault")


def test_device_faults_become_alarms_and_go_inactive_when_cleared() -> None:
    a = make()
    a.on_faults("/sim/faults", [fault("door_open", False), fault("gripper_fault", False)], 1.0)
    assert a.alarms() == []                                   # inactive faults are no alarms
    a.on_faults("/sim/faults", [fault("door_open", True, since=0.5), fault("gripper_fault", False)], 2.0)
    (door,) = a.alarms()
    assert (door.id, door.text, door.severity, door.source, door.first_seen) == \
        ("device.door_open", "door_open text", ERROR, "device", 0.5)
    a.on_faults("/sim/faults", [fault("door_open", False, since=3.0), fault("gripper_fault", False)], 3.0)
    assert listed(a) == {"device.door_open": False}
    # ROS times (anything with to_sec) work as the stamp too
    a.on_faults("/sim/faults", [fault("gripper_fault", True, since=SimpleNamespace(to_sec=lambda: 3.5))], 4.0)
    assert a.table.get("device.gripper_fault").first_seen == 3.5


def test_force_limit_on_the_norm_with_hysteresis_and_unwatched_topics_ignored() -> None:
    a = make()
    assert not a.on_wrench(WRENCH, wrench(60, 50, -10), 1.0)    # |F| = 78.7 N: under 80
    assert a.alarms() == []
    assert a.on_wrench(WRENCH, wrench(60, 50, -20), 1.0)        # |F| = 80.6 N: over 80 (no axis is)
    (f,) = a.alarms()
    assert (f.id, f.severity, f.active, f.source) == ("force.limit", ERROR, True, "force")
    assert "81 N" in f.text and "80 N" in f.text and WRENCH in f.text
    assert not a.on_wrench(WRENCH, wrench(0, 0, -75), 2.0)      # 75 N: under the limit, above the 72 N clear level
    assert a.alarms()[0].active and "81 N" in a.alarms()[0].text  # the text keeps the tripping value
    assert a.on_wrench(WRENCH, wrench(0, 0, -71), 3.0)
    assert listed(a) == {"force.limit": False}
    assert not a.on_wrench("/other/wrench", wrench(0, 0, -500), 4.0)
    assert listed(a) == {"force.limit": False}


def test_force_supervision_is_off_without_a_limit_and_clear_level_is_configurable() -> None:
    a = Alarms(parse_alarms(cell()), 0.0)
    assert not a.on_wrench(WRENCH, wrench(0, 0, -500), 1.0) and a.alarms() == []
    a = make(force_clear_n=50)
    a.on_wrench(WRENCH, wrench(0, 0, 90), 1.0)
    a.on_wrench(WRENCH, wrench(0, 0, 60), 2.0)
    assert listed(a) == {"force.limit": True}
    a.on_wrench(WRENCH, wrench(0, 0, 49), 3.0)
    assert listed(a) == {"force.limit": False}


def test_incomplete_modules_become_warnings_from_dicts_or_objects() -> None:
    a = make()
    a.on_modules([{"name": "vision", "state": "incomplete"}, {"name": "sim", "state": "active"},
                  SimpleNamespace(name="gripper", state="transitioning")], 1.0)
    (m,) = a.alarms()
    assert (m.id, m.severity, m.source, m.active) == ("module.vision", WARNING, "modules", True)
    assert m.text == "module vision is incomplete: some of its nodes are not running"
    a.on_modules([SimpleNamespace(name="vision", state="active")], 2.0)
    assert listed(a) == {"module.vision": False}
    # the modules node's fields: its message, else the nodes that are not alive
    a.on_modules([{"name": "vision", "state": "incomplete", "nodes": ["/cam", "/detector"], "alive": [True, False]}],
                 3.0)
    assert a.table.get("module.vision").text == "module vision is incomplete: not running: /detector"
    a.on_modules([{"name": "vision", "state": "incomplete", "message": "launch did not settle within 10 s"}], 4.0)
    assert a.table.get("module.vision").text == "module vision is incomplete: launch did not settle within 10 s"


def test_severity_overrides_exact_ids_win_over_globs() -> None:
    a = make(severity={"module.*": "error", "robot.*": "warning", "robot.arm.emergency_stop": "error"})
    a.on_modules([{"name": "vision", "state": "incomplete"}], 1.0)
    a.on_robot_state("arm", robot(safety="PROTECTIVE_STOP"), 1.0)
    assert a.table.get("module.vision").severity == ERROR
    assert a.table.get("robot.arm.protective_stop").severity == WARNING
    a.on_robot_state("arm", robot(safety="ROBOT_EMERGENCY_STOP"), 2.0)
    assert a.table.get("robot.arm.emergency_stop").severity == ERROR


def test_silent_robot_driver_and_wrench_raise_alarms_and_clear_when_back() -> None:
    a = make(timeout_s=2)
    assert not a.tick(50.0)                                   # never heard: the source may not exist
    a.on_robot_state("arm", robot(safety="REDUCED"), 100.0)
    a.on_wrench(WRENCH, wrench(), 100.0)
    assert not a.tick(101.9)
    assert a.tick(102.5)
    assert listed(a) == {"robot.arm.reduced_mode": False, "robot.arm.no_state": True, "force.no_data": True}
    assert a.table.get("robot.arm.no_state").severity == ERROR and a.table.get("force.no_data").severity == WARNING
    st = a.status()
    assert (st.controller_connected, st.safety_mode, st.robot_mode) == (False, "", "")
    assert not a.tick(103.0)                                  # raised once
    a.on_robot_state("arm", robot(), 104.0)
    a.on_wrench(WRENCH, wrench(), 104.0)
    assert listed(a) == {"robot.arm.reduced_mode": False, "robot.arm.no_state": False, "force.no_data": False}
    assert Alarms(parse_alarms(cell(timeout_s=0)), 0.0).tick(1e9) is False


def test_an_expected_driver_that_never_publishes_raises_no_state_after_the_grace() -> None:
    c = cell(force_limit_n=80, timeout_s=2, startup_grace_s=10)
    c["manual"] = {"groups": [{"name": "arm", "joints": ["elbow_joint"]}]}  # the cell has a robot driver
    a = Alarms(parse_alarms(c), 100.0)
    assert not a.tick(109.0) and a.alarms() == []
    assert a.tick(110.5)
    assert a.alarms()[0].id == "robot.arm.no_state" and a.alarms()[0].text == (
        "Robot arm: no robot state from the driver on /cell/manual/arm/state since the start (10 s)")
    a.on_robot_state("arm", robot(), 111.0)
    assert listed(a) == {"robot.arm.no_state": False}
    assert not Alarms(parse_alarms(cell(timeout_s=2)), 100.0).tick(200.0)  # no driver in the cell: no alarm


def test_the_drivers_first_connection_after_start_is_no_alarm_until_the_grace_is_over() -> None:
    a = make(now=100.0, startup_grace_s=10)
    down = robot(connected=False, safety="", mode="NO_CONTROLLER")
    assert not a.on_robot_state("arm", down, 101.0) and a.alarms() == []   # still connecting
    assert not a.tick(102.5)
    assert a.on_robot_state("arm", robot(), 106.0) is False and a.alarms() == []  # connected: nothing ever listed
    assert a.on_robot_state("arm", down, 107.0)                              # connected once: now it is "lost"
    assert listed(a) == {"robot.arm.disconnected": True}
    b = make(now=100.0, startup_grace_s=10)
    b.on_robot_state("arm", down, 101.0)
    b.on_robot_state("arm", down, 109.0)
    assert b.alarms() == []
    assert b.tick(110.5)                                              # never connected within the grace
    assert listed(b) == {"robot.arm.disconnected": True} and b.table.get("robot.arm.disconnected").first_seen == 110.5


# ---------------------------------------------------------------------------------------------- reset
def test_reset_clears_inactive_keeps_active_and_says_what() -> None:
    a = make()
    a.on_faults("/sim/faults", [fault("door_open", True), fault("gripper_fault", True)], 1.0)
    a.on_robot_state("arm", robot(safety="PROTECTIVE_STOP"), 1.0)
    a.on_faults("/sim/faults", [fault("door_open", False), fault("gripper_fault", True)], 2.0)
    ok, message = a.reset()
    assert ok and message == ("cleared 1 inactive alarm (device.door_open); "
                              "2 still active (device.gripper_fault, robot.arm.protective_stop)")
    assert listed(a) == {"robot.arm.protective_stop": True, "device.gripper_fault": True}
    assert a.table.get("device.gripper_fault").first_seen == 1.0  # an active alarm keeps its history
    a.on_robot_state("arm", robot(), 3.0)
    a.on_faults("/sim/faults", [fault("gripper_fault", False)], 3.0)
    assert a.reset() == (True, "cleared 2 inactive alarms (device.gripper_fault, robot.arm.protective_stop)")
    assert a.alarms() == []
    assert a.reset() == (True, "no inactive alarm to clear")


# ---------------------------------------------------------------------------------------------- status
def test_overall_status_follows_the_most_urgent_condition() -> None:
    a = make()
    st = a.status()
    assert (st.status, st.text, st.active_count, st.inactive_count, st.highest_severity) == \
        ("normal", "no active alarm", 0, 0, -1)
    a.on_robot_state("arm", robot(mode="POWER_OFF", safety="NORMAL"), 1.0)
    assert (a.status().status, a.status().highest_severity, a.status().robot_mode) == ("normal", INFO, "POWER_OFF")
    a.on_robot_state("arm", robot(safety="REDUCED"), 2.0)
    st = a.status()
    assert (st.status, st.highest_severity, st.safety_mode, st.controller_connected) == \
        ("warning", WARNING, "REDUCED", True)
    assert (st.active_count, st.inactive_count) == (1, 1)       # power_off went inactive
    a.on_faults("/sim/faults", [fault("gripper_fault", True)], 3.0)
    assert (a.status().status, a.status().text) == ("fault", "gripper_fault text")
    for safety, status in (("SAFEGUARD_STOP", "safeguard stop"), ("PROTECTIVE_STOP", "protective stop"),
                           ("SYSTEM_EMERGENCY_STOP", "emergency stop")):
        a.on_robot_state("arm", robot(safety=safety), 4.0)
        assert a.status().status == status
    a.on_faults("/sim/faults", [], 5.0)
    a.on_robot_state("arm", robot(), 5.0)
    a.reset()
    assert a.status().status == "normal" and a.status().inactive_count == 0


def test_outputs_publish_on_change_and_once_a_period() -> None:
    a = make(now=0.0, publish_period_s=1.0)
    alarms, status = a.outputs(0.0)
    assert alarms == [] and status.status == "normal"           # the first call publishes both
    assert a.outputs(0.1) == (None, None)                       # nothing changed
    a.on_robot_state("arm", robot(safety="REDUCED"), 0.2)
    alarms, status = a.outputs(0.2)
    assert [x.id for x in alarms] == ["robot.arm.reduced_mode"] and status.status == "warning"
    a.on_robot_state("arm", robot(safety="REDUCED", mode="IDLE"), 0.3)
    alarms, status = a.outputs(0.3)
    assert alarms is None and status.robot_mode == "IDLE"       # status-only change
    a.tick(1.05)
    alarms, status = a.outputs(1.05)                            # the period: both again, last seen refreshed
    assert alarms[0].last_seen == 1.05 and status is not None


# ---------------------------------------------------------------------------------------------- operation mode
def test_mode_goes_to_alarm_on_an_error_and_back_when_it_clears() -> None:
    a = make()
    a.on_faults("/sim/faults", [fault("door_open", True)], 1.0)
    assert a.mode_request() is None                             # the mode is not known yet
    a.on_mode("running", "ui:alice")
    req = a.mode_request()
    assert req.mode == "alarm" and "device.door_open" in req.reason
    a.mode_done(req, False)                                     # the service was down: asked again
    assert a.mode_request() == req
    a.mode_done(req, True)
    assert a.mode_request() is None                             # not asked again while the topic catches up
    a.on_mode("alarm", "alarms")
    assert a.mode_request() is None                             # still an error
    a.on_faults("/sim/faults", [fault("door_open", False)], 2.0)
    back = a.mode_request()
    assert back == ModeRequest("running", "no error alarm active any more")
    a.mode_done(back, True)
    a.on_mode("running", "alarms")
    assert a.mode_request() is None
    # inactive error alarms (not reset yet) do not hold the mode
    assert listed(a) == {"device.door_open": False}


def test_warnings_do_not_change_the_mode() -> None:
    a = make()
    a.on_mode("running", "ui")
    a.on_robot_state("arm", robot(safety="REDUCED"), 1.0)
    a.on_modules([{"name": "vision", "state": "incomplete"}], 1.0)
    assert a.mode_request() is None
    a = make(severity={"module.*": "error"})
    a.on_mode("running", "ui")
    a.on_modules([{"name": "vision", "state": "incomplete"}], 1.0)
    assert a.mode_request().mode == "alarm"


def test_mode_changed_by_someone_else_is_not_fought_nor_restored() -> None:
    k = ModeKeeper()
    k.on_mode("running", "ui")
    assert k.decide({"e1"}).mode == "alarm"
    k.on_mode("alarm", "alarms")
    k.on_mode("manual", "ui:bob")                                # the operator recovers the cell
    assert k.decide({"e1"}) is None                              # the same error: not switched again
    assert k.decide(set()) is None                               # cleared: manual stays
    assert k.decide({"e2"}).mode == "alarm"                      # a new error switches again...
    k.on_mode("alarm", "alarms")
    assert k.decide(set()) == ModeRequest("manual", "no error alarm active any more")  # ...and restores manual
    # alarm set by someone else: not ours to give back
    k = ModeKeeper()
    k.on_mode("alarm", "ui")
    assert k.decide({"e1"}) is None and k.decide(set()) is None
    # someone else sets alarm over ours, then the error clears: left alone
    k = ModeKeeper()
    k.on_mode("idle", "startup")
    assert k.decide({"e1"}).mode == "alarm"
    k.on_mode("alarm", "ui:carol")
    assert k.decide(set()) is None


def test_mode_switching_off_when_the_cell_has_no_alarm_mode() -> None:
    c = cell(force_limit_n=80)
    c["operation_mode"] = dict(MODE, modes=["idle", "running"])
    a = Alarms(parse_alarms(c), 0.0)
    a.on_mode("running", "ui")
    a.on_faults("/sim/faults", [fault("door_open", True)], 1.0)
    assert a.mode_request() is None
    assert "no 'alarm'" in alarm_mode_problem(c)
    assert parse_alarms(cell(alarm_mode="")).alarm_mode == "" and alarm_mode_problem(cell(alarm_mode="")) is not None
    assert alarm_mode_problem(cell()) is None


# ---------------------------------------------------------------------------------------------- the cell file
def test_demo_cell_section() -> None:
    cfg = parse_alarms(yaml.safe_load(DEMO.read_text()))
    assert cfg.force_limit_n == 80 and cfg.force_clear == pytest.approx(72)
    assert cfg.wrench_topics == ("/cell/wrench",)              # from the sensors of type WrenchStamped
    assert cfg.fault_topics == ("/sim/faults",)
    assert cfg.robot_expected and cfg.timeout_s == 2 and cfg.startup_grace_s == 10
    assert cfg.robot_state_topics == (("arm", "/cell/manual/arm/state"),)   # one per motion group
    assert (cfg.alarm_mode, cfg.mode_topic, cfg.set_mode_service) == ("alarm", "/cell/mode", "/cell/set_mode")


def test_defaults_and_errors_name_the_field() -> None:
    cfg = parse_alarms({"operation_mode": MODE})
    assert cfg == AlarmsConfig(alarm_mode="alarm", modes=tuple(MODE["modes"]))
    assert cfg.force_limit_n is None and cfg.wrench_topics == () and cfg.timeout_s == 2.0
    assert parse_alarms(cell(wrench_topics=["/a", "/b"])).wrench_topics == ("/a", "/b")
    for section, where in (({"force_limit_n": -1}, "alarms.force_limit_n"),
                           ({"force_limit_n": "high"}, "alarms.force_limit_n"),
                           ({"force_limit_n": 80, "force_clear_n": 90}, "alarms.force_clear_n"),
                           ({"force_clear_n": 50}, "alarms.force_clear_n"),
                           ({"fault_topics": ["sim/faults"]}, "alarms.fault_topics[0]"),
                           ({"severity": {"robot.*": "fatal"}}, "alarms.severity.robot.*"),
                           ({"timeout_s": -1}, "alarms.timeout_s"),
                           ({"robot_state_topics": {"legs": "/x"}}, "alarms.robot_state_topics.legs"),
                           ({"robot_state_topics": ["/x"]}, "alarms.robot_state_topics")):
        with pytest.raises(ConfigError, match=rf"^{where}:".replace(".", r"\.").replace("*", r"\*")
                           .replace("[", r"\[").replace("]", r"\]")):
            parse_alarms(cell(**section))


def test_two_wrench_topics_get_one_alarm_each() -> None:
    a = make(wrench_topics=["/left/wrench", "/right/wrench"])
    a.on_wrench("/left/wrench", wrench(0, 0, 100), 1.0)
    a.on_wrench("/right/wrench", wrench(0, 0, 100), 1.0)
    assert set(listed(a)) == {"force.limit:/left/wrench", "force.limit:/right/wrench"}


# ---------------------------------------------------------------------------------------------- several groups
TWIN = {"groups": [{"name": "left", "joints": ["left_elbow_joint"]}, {"name": "right", "joints": ["right_elbow_joint"]}]}


def twin(now: float = 100.0, **alarms) -> Alarms:
    c = cell(**alarms)
    c["manual"] = TWIN
    return Alarms(parse_alarms(c), now)


def test_every_group_is_watched_on_its_own_topic_with_its_own_ids() -> None:
    cfg = parse_alarms({**cell(), "manual": TWIN})
    assert cfg.robot_state_topics == (("left", "/cell/manual/left/state"), ("right", "/cell/manual/right/state"))
    moved = parse_alarms({**cell(robot_state_topics={"right": "/other/right/state"}), "manual": TWIN})
    assert moved.robot_state_topics == (("left", "/cell/manual/left/state"), ("right", "/other/right/state"))
    a = twin(now=0.0)
    a.on_robot_state("left", robot(), 1.0)
    a.on_robot_state("right", robot(safety="PROTECTIVE_STOP"), 1.0)
    (alarm,) = a.alarms()
    assert (alarm.id, alarm.severity, alarm.source) == ("robot.right.protective_stop", ERROR, "robot")
    assert alarm.text == "Robot right: protective stop: the robot stopped; clear the cause, then unlock it"
    st = a.status()
    assert (st.status, st.safety_mode, st.robot_mode, st.controller_connected) == \
        ("protective stop", "PROTECTIVE_STOP", "RUNNING", True)
    a.on_robot_state("left", robot(connected=False, safety="", mode="NO_CONTROLLER", host="127.0.2.1"), 2.0)
    assert listed(a) == {"robot.left.disconnected": True, "robot.right.protective_stop": True}
    assert a.table.get("robot.left.disconnected").text == "Robot left: robot controller at 127.0.2.1 is unreachable"
    assert a.status().controller_connected is False            # one arm's controller is enough to say so
    a.on_robot_state("right", robot(), 3.0)                     # the right arm's stop clears; the left one stays
    assert listed(a) == {"robot.left.disconnected": True, "robot.right.protective_stop": False}
    assert a.status().status == "fault" and a.table.active_ids(ERROR) == {"robot.left.disconnected"}


def test_a_silent_group_raises_its_own_no_state_and_the_other_keeps_its_modes() -> None:
    a = twin(now=100.0, timeout_s=2, startup_grace_s=10)
    a.on_robot_state("left", robot(safety="REDUCED"), 101.0)
    a.on_robot_state("right", robot(), 101.0)
    for t in (102.0, 103.0, 104.0):
        a.on_robot_state("left", robot(safety="REDUCED"), t)   # left keeps talking, right fell silent at 101
    assert a.tick(104.0)
    assert listed(a) == {"robot.left.reduced_mode": True, "robot.right.no_state": True}
    assert a.table.get("robot.right.no_state").text == \
        "Robot right: no robot state from the driver on /cell/manual/right/state for 2 s"
    st = a.status()
    assert (st.safety_mode, st.robot_mode, st.controller_connected) == ("REDUCED", "", False)  # right: unknown
    a.on_robot_state("right", robot(), 105.0)
    assert listed(a) == {"robot.left.reduced_mode": True, "robot.right.no_state": False}


def test_a_group_that_never_publishes_raises_no_state_after_the_grace_alone() -> None:
    a = twin(now=100.0, timeout_s=2, startup_grace_s=10)
    for t in range(101, 112):
        a.on_robot_state("left", robot(), float(t))
    assert a.tick(110.5)
    assert listed(a) == {"robot.right.no_state": True}
    assert "since the start (10 s)" in a.table.get("robot.right.no_state").text


def test_severity_globs_reach_every_group() -> None:
    a = twin(now=0.0, severity={"robot.*.reduced_mode": "info", "robot.left.power_off": "warning"})
    a.on_robot_state("left", robot(safety="REDUCED", mode="POWER_OFF"), 1.0)
    a.on_robot_state("right", robot(safety="REDUCED", mode="POWER_OFF"), 1.0)
    sev = {x.id: x.severity for x in a.alarms()}
    assert sev == {"robot.left.reduced_mode": INFO, "robot.right.reduced_mode": INFO,
                   "robot.left.power_off": WARNING, "robot.right.power_off": INFO}


# ---------------------------------------------------------------------------------------------- across a restart
def _restarted(memory: dict, now: float = 200.0, **alarms) -> Alarms:
    """A new core (the node after its restart) given the memory the old one saved, through its JSON file."""
    import json
    b = make(now=now, **alarms)
    assert b.restore(json.loads(json.dumps(memory))) is None
    return b


def _in_alarm_from_running() -> Alarms:
    a = make()
    a.on_mode("running", "ui:alice")
    a.on_faults("/sim/faults", [fault("door_open", True)], 1.0)
    req = a.mode_request(1.0)
    assert req.mode == "alarm"
    a.mode_done(req, True)
    a.on_mode("alarm", "alarms")
    return a


def test_the_mode_an_alarm_replaced_survives_a_restart_of_the_node() -> None:
    a = _in_alarm_from_running()
    assert a.memory() == {"alarm_mode": "alarm", "previous": "running", "seen": ["device.door_open"],
                          "want_alarm": False}
    # Without the memory (what a restart did before): the mode stays alarm for good once the fault clears.
    fresh = make(now=200.0)
    fresh.on_mode("alarm", "alarms")
    fresh.on_faults("/sim/faults", [fault("door_open", False)], 200.5)
    assert fresh.mode_request(201.0) is None
    # With it: the fault cleared while the node was down; once the sources reported, the mode goes back.
    b = _restarted(a.memory())
    b.on_mode("alarm", "alarms")                                   # the latched mode topic
    assert b.mode_request(200.1) is None                            # nothing reported yet: nothing given back
    b.on_faults("/sim/faults", [fault("door_open", False)], 200.2)
    b.on_wrench(WRENCH, wrench(), 200.2)
    assert b.mode_request(200.3) is None                            # the modules have not reported yet
    b.on_modules([], 200.4)
    assert b.mode_request(200.5) == ModeRequest("running", "no error alarm active any more")


def test_after_a_restart_an_alarm_still_active_keeps_the_mode_and_clears_it_later() -> None:
    b = _restarted(_in_alarm_from_running().memory(), timeout_s=2, startup_grace_s=5)
    b.on_mode("alarm", "alarms")
    b.on_faults("/sim/faults", [fault("door_open", True)], 200.5)
    b.on_wrench(WRENCH, wrench(), 200.5)
    b.on_modules([], 200.5)
    assert b.settled(200.6) and b.mode_request(200.6) is None       # known again and still active: alarm stays
    assert b.mode_request(206.0) is None
    b.on_faults("/sim/faults", [fault("door_open", False)], 207.0)
    assert b.mode_request(207.1) == ModeRequest("running", "no error alarm active any more")


def test_after_a_restart_the_grace_ends_the_wait_for_silent_sources() -> None:
    b = _restarted(_in_alarm_from_running().memory(), timeout_s=2, startup_grace_s=5)
    b.on_mode("alarm", "alarms")
    b.on_faults("/sim/faults", [], 201.0)                           # no wrench, no modules ever
    assert b.mode_request(204.9) is None
    assert b.mode_request(205.1) == ModeRequest("running", "no error alarm active any more")


def test_after_a_restart_a_robot_counts_once_its_state_is_not_held_back() -> None:
    c = cell(force_limit_n=80, timeout_s=2, startup_grace_s=10)
    c["manual"] = {"groups": [{"name": "arm", "joints": ["elbow_joint"]}]}
    a = Alarms(parse_alarms(c), 0.0)
    a.on_mode("running", "ui")
    a.on_robot_state("arm", robot(), 1.0)
    a.on_robot_state("arm", robot(connected=False, safety="", mode=""), 2.0)   # connection lost: an error
    req = a.mode_request(2.0)
    a.mode_done(req, True)
    a.on_mode("alarm", "alarms")
    b = Alarms(parse_alarms(c), 100.0)
    assert b.restore(a.memory()) is None
    b.on_mode("alarm", "alarms")
    b.on_faults("/sim/faults", [], 100.1)
    b.on_wrench(WRENCH, wrench(), 100.1)
    b.on_modules([], 100.1)
    b.on_robot_state("arm", robot(connected=False, safety="", mode=""), 100.2)  # held back: first connection
    assert b.mode_request(100.3) is None
    b.on_robot_state("arm", robot(), 101.0)
    assert b.mode_request(101.1) == ModeRequest("running", "no error alarm active any more")


def test_after_a_restart_an_error_already_acted_on_does_not_switch_again_but_a_new_one_does_at_once() -> None:
    a = _in_alarm_from_running()
    a.on_mode("manual", "ui:bob")                                   # the operator recovers the cell
    a.mode_request(2.0)
    assert a.memory() == {"alarm_mode": "alarm", "previous": None, "seen": ["device.door_open"], "want_alarm": False}
    b = _restarted(a.memory())
    b.on_mode("manual", "ui:bob")
    b.on_faults("/sim/faults", [fault("door_open", True)], 200.1)
    assert b.mode_request(200.2) is None                            # not fought after the restart either
    b.on_faults("/sim/faults", [fault("door_open", True), fault("estop", True)], 200.3)
    req = b.mode_request(200.4)                                     # a new error: at once, not after the wait
    assert req.mode == "alarm" and "device.estop" in req.reason
    # A switch that was due when the node stopped is still due after its restart.
    c = make()
    c.on_mode("running", "ui")
    c.on_faults("/sim/faults", [fault("door_open", True)], 1.0)
    assert c.mode_request(1.0).mode == "alarm"                     # asked, never answered: the node stopped
    assert c.memory()["want_alarm"] is True
    d = _restarted(c.memory())
    d.on_mode("running", "ui")
    d.on_faults("/sim/faults", [fault("door_open", True)], 200.1)
    assert d.mode_request(200.2).mode == "alarm"


@pytest.mark.parametrize("change, why", [
    ({"previous": "spinning"}, r"previous: 'spinning' is not a mode to give back .*stale"),
    ({"previous": "alarm"}, r"previous: 'alarm' is not a mode to give back"),
    ({"previous": 3}, r"previous: expected a mode name or null, got 3"),
    ({"alarm_mode": "fault"}, r"saved for alarm mode 'fault', the cell file's is 'alarm' \(stale"),
    ({"seen": "door"}, r"seen: expected a list of alarm ids"),
    ({"seen": [1]}, r"seen: expected a list of alarm ids"),
    ({"want_alarm": "yes"}, r"want_alarm: expected true or false"),
])
def test_a_stale_or_malformed_memory_is_refused_and_the_core_starts_clean(change: dict, why: str) -> None:
    memory = dict(_in_alarm_from_running().memory(), **change)
    b = make(now=200.0)
    assert re.search(why, b.restore(memory))
    assert b.memory() == {"alarm_mode": "alarm", "previous": None, "seen": [], "want_alarm": False}
    assert b.settled(200.0)                                         # nothing remembered: nothing to wait for


# ---------------------------------------------------------------------------------------------- codes for the app
CATALOGUE = Path(__file__).resolve().parents[4] / "app" / "messages" / "alarms"


def every_coded_alarm() -> list:
    """Every kind of alarm the core raises, through its inputs (each safety and robot mode, a motion fault, a lost
    controller, the force limit and its silence, a silent driver (heard before, and never), modules, diagnostics)."""
    from cell_nodes.alarms.sources import ROBOT_MODE_ALARMS, SAFETY_ALARMS
    from cell_nodes.diagnostics import DiagStatus, ERROR as D_ERROR, STALE as D_STALE, WARN as D_WARN
    from cell_nodes.alarms.sources import diagnostic_conditions, module_conditions
    from cell_nodes.alarms.config import DiagRule
    out = []
    for safety in [*SAFETY_ALARMS, "ODD_MODE"]:
        out += robot_conditions_of(robot(safety=safety))
    for mode in ROBOT_MODE_ALARMS:
        out += robot_conditions_of(robot(mode=mode))
    out += robot_conditions_of(robot(connected=False)) + robot_conditions_of({**robot(), "fault": "goal aborted"})
    a = make(timeout_s=2)
    a.on_robot_state("arm", robot(), 100.0)
    a.on_wrench(WRENCH, wrench(fx=300.0), 100.0)
    a.tick(103.0)
    out += a.alarms()
    c = cell(force_limit_n=80, timeout_s=2, startup_grace_s=10)
    c["manual"] = {"groups": [{"name": "arm", "joints": ["elbow_joint"]}]}
    b = Alarms(parse_alarms(c), 100.0)
    b.tick(111.0)
    out += b.alarms()
    out += module_conditions([{"name": "vision", "state": "incomplete", "nodes": ["/a", "/b"], "alive": [True, False]},
                              {"name": "io", "state": "incomplete", "message": "launch timed out"},
                              {"name": "cam", "state": "incomplete"}])
    rule = DiagRule("*", WARNING, ERROR, WARNING)
    out += diagnostic_conditions([DiagStatus("cam", D_WARN, ""), DiagStatus("cam2", D_ERROR, ""),
                                  DiagStatus("cam3", D_STALE, "last words")], [rule], 5.0)
    return out


def robot_conditions_of(state: dict) -> list:
    from cell_nodes.alarms.sources import robot_conditions
    return robot_conditions("arm", state)[1]


def test_every_alarm_the_node_raises_has_a_code_the_app_says_in_every_language_with_the_same_parameters() -> None:
    import json
    alarms = every_coded_alarm()
    codes = {x.code for x in alarms}
    assert {"robot.safety.protective_stop", "robot.mode.power_off", "robot.disconnected", "robot.motion_fault",
            "robot.safety_mode", "force.limit", "force.no_data", "robot.no_state", "robot.no_state_since_start",
            "module.nodes_down", "module.incomplete", "module.incomplete_because", "diagnostics.stale", "diagnostics.warning",
            "diagnostics.error"} <= codes
    assert all(x.code for x in alarms), [x.id for x in alarms if not x.code]
    for lang in ("en", "es", "fi", "de"):
        catalogue = json.loads((CATALOGUE / f"{lang}.json").read_text())
        for x in alarms:
            key = "alarms_code_" + x.code.replace(".", "_")
            assert key in catalogue, f"{lang}: no {key} for {x.id}"
            assert set(re.findall(r"\{(\w+)\}", catalogue[key])) == {k for k, _ in x.params}, (lang, key, x.params)
    # The English catalogue says what the node's own English text says.
    en = json.loads((CATALOGUE / "en.json").read_text())
    for x in alarms:
        assert en["alarms_code_" + x.code.replace(".", "_")].format(**dict(x.params)) == x.text, x.id


def test_the_status_names_its_alarm_with_code_and_parameters() -> None:
    a = make()
    a.on_robot_state("arm", robot(safety="PROTECTIVE_STOP"), 100.0)
    st = a.status()
    assert (st.alarm_id, st.code, st.params) == ("robot.arm.protective_stop", "robot.safety.protective_stop",
                                                 (("group", "arm"),))
    a.on_robot_state("arm", robot(), 101.0)
    assert a.status().code == "" and a.status().text == "no active alarm"
