"""Diagnostics without ROS: the statuses heard with the silent ones STALE (cell_nodes.diagnostics), the cell file's
rules turning WARN/ERROR/STALE into alarms (alarms config, sources, core), a module stopped on purpose leaving no
stale alarm, and what the demo's drivers report (the robot driver, the vision monitor, the system monitor)."""
from __future__ import annotations

import pytest

from cell_nodes.alarms.config import ConfigError, DiagRule, parse_alarms
from cell_nodes.alarms.core import Alarms
from cell_nodes.alarms.sources import diagnostic_conditions, diagnostics_alarm_id
from cell_nodes.alarms.table import ERROR, INFO, WARNING
from cell_nodes.diagnostics import ERROR as D_ERROR, OK, STALE, WARN, DiagnosticsTracker, statuses_of
from cell_nodes.manual.diagnostics import RateMeter, driver_diagnostic
from cell_nodes.manual.driver import DriverState
from cell_nodes.modules.demo import load_diagnostic, vision_diagnostic

MODE = {"topic": "/cell/mode", "set_service": "/cell/set_mode", "modes": ["idle", "running", "alarm", "manual"]}
RULES = [{"match": "vision: *", "stale": "error"}, {"match": "manual: *", "warn": "none", "error": "none"},
         {"match": "*", "warn": "info", "error": "warning", "stale": "none"}]


def array(*statuses: tuple) -> dict:
    return {"status": [{"name": n, "level": lvl, "message": m, "hardware_id": "",
                        "values": [{"key": "rate", "value": "1"}]} for n, lvl, m in statuses]}


def alarms(now: float = 0.0, **diag) -> Alarms:
    return Alarms(parse_alarms({"operation_mode": MODE, "alarms": {"diagnostics": {"rules": RULES, **diag}}}), now)


def listed(a: Alarms) -> dict[str, tuple[bool, int]]:
    return {x.id: (x.active, x.severity) for x in a.alarms() if x.source == "diagnostics"}


def test_the_tracker_keeps_the_latest_of_each_name_and_marks_silent_ones_stale() -> None:
    t = DiagnosticsTracker(stale_s=5)
    t.add(statuses_of(array(("b: x", OK, "fine"), ("a: y", WARN, "slow")), "/n1", 10.0))
    t.add(statuses_of(array(("b: x", D_ERROR, "broken")), "/n1", 12.0))
    now = t.current(14.0)
    assert [(s.name, s.level, s.message) for s in now] == [("a: y", WARN, "slow"), ("b: x", D_ERROR, "broken")]
    assert now[0].values == (("rate", "1"),) and now[0].node == "/n1"
    later = t.current(16.0)                   # a: y silent for 6 s, b: x for 4 s
    assert [(s.name, s.level, s.message) for s in later] == [("a: y", STALE, "slow"), ("b: x", D_ERROR, "broken")]
    assert t.forget_nodes(["/n1"]) == ["a: y", "b: x"] and t.current(16.0) == []


def test_the_tracker_is_bounded_by_names() -> None:
    t = DiagnosticsTracker(max_names=3)
    for i in range(10):
        t.add(statuses_of(array((f"s{i}", OK, "")), "/n", float(i)))
    assert [s.name for s in t.current(9.0)] == ["s7", "s8", "s9"]


def test_an_unknown_level_counts_as_an_error_and_byte_levels_are_read() -> None:
    [s] = statuses_of({"status": [{"name": "x", "level": 9, "message": ""}]}, "", 0.0)
    [b] = statuses_of({"status": [{"name": "y", "level": b"\x01", "message": ""}]}, "", 0.0)
    assert (s.level, b.level) == (D_ERROR, WARN)


def test_rules_first_match_decides_the_severity_per_level_and_ok_raises_nothing() -> None:
    rules = parse_alarms({"alarms": {"diagnostics": {"rules": RULES}}}).diagnostics_rules
    assert rules[0] == DiagRule("vision: *", WARNING, ERROR, ERROR)
    t = DiagnosticsTracker()
    t.add(statuses_of(array(("vision: camera", WARN, "dark"), ("manual: arm controller", D_ERROR, "lost"),
                            ("other", D_ERROR, "boom"), ("fine", OK, "")), "/n", 0.0))
    got = {c.id: (c.severity, c.text) for c in diagnostic_conditions(t.current(1.0), rules, 5.0)}
    assert got == {"diagnostics.vision_camera": (WARNING, "vision: camera: dark"),
                   "diagnostics.other": (WARNING, "other: boom")}
    stale = {c.id: (c.severity, c.text) for c in diagnostic_conditions(t.current(10.0), rules, 5.0)}
    assert stale == {"diagnostics.vision_camera": (ERROR, "vision: camera: no report for 5 s (stale; last: dark)"),
                     "diagnostics.manual_arm_controller": (WARNING, "manual: arm controller: no report for 5 s "
                                                                    "(stale; last: lost)")}   # stale's default
    assert diagnostics_alarm_id("System Monitor: CPU load (1 min)") == "diagnostics.system_monitor_cpu_load_1_min"


def test_a_silent_status_raises_its_stale_alarm_and_clears_when_it_reports_again() -> None:
    a = alarms()
    a.on_diagnostics(array(("vision: camera", OK, "ok")), "/vision_monitor", 1.0)
    assert listed(a) == {}
    a.tick(5.0)
    assert listed(a) == {}
    assert a.tick(7.0)                      # 6 s silent: stale
    assert listed(a) == {"diagnostics.vision_camera": (True, ERROR)}
    a.on_diagnostics(array(("vision: camera", OK, "ok")), "/vision_monitor", 8.0)
    assert listed(a) == {"diagnostics.vision_camera": (False, ERROR)}   # inactive until a reset
    a.reset()
    assert listed(a) == {}


def test_a_module_stopped_on_purpose_leaves_no_stale_alarm_but_a_killed_node_does() -> None:
    a = alarms()
    a.on_diagnostics(array(("vision: camera", OK, "ok")), "/vision_monitor", 1.0)
    a.on_modules([{"name": "Vision", "state": "incomplete", "nodes": ["/vision", "/vision_monitor"]}], 2.0)
    a.tick(10.0)
    assert listed(a)["diagnostics.vision_camera"] == (True, ERROR)      # killed: stale
    a.on_modules([{"name": "Vision", "state": "inactive", "nodes": ["/vision", "/vision_monitor"]}], 11.0)
    assert listed(a)["diagnostics.vision_camera"] == (False, ERROR)     # stopped: forgotten, the alarm inactive
    a.on_diagnostics(array(("vision: camera", WARN, "no image")), "/vision_monitor", 11.5)   # a last report
    a.tick(30.0)
    assert listed(a)["diagnostics.vision_camera"][0] is False
    a.on_modules([{"name": "Vision", "state": "active", "nodes": ["/vision", "/vision_monitor"]}], 31.0)
    a.on_diagnostics(array(("vision: camera", WARN, "no image")), "/vision_monitor", 31.5)
    assert listed(a)["diagnostics.vision_camera"] == (True, WARNING)


def test_without_rules_diagnostics_raise_nothing_and_bad_rules_name_the_field() -> None:
    a = Alarms(parse_alarms({"alarms": {}}), 0.0)
    a.on_diagnostics(array(("x", D_ERROR, "boom")), "/n", 1.0)
    assert listed(a) == {}
    assert parse_alarms({"alarms": {}}).diagnostics_topic is None
    assert parse_alarms({"alarms": {"diagnostics": {}}}).diagnostics_topic == "/diagnostics"
    with pytest.raises(ConfigError, match=r"alarms.diagnostics.rules\[0\].stale: expected one of"):
        parse_alarms({"alarms": {"diagnostics": {"rules": [{"match": "x", "stale": "loud"}]}}})
    with pytest.raises(ConfigError, match=r"alarms.diagnostics.rules\[1\].match"):
        parse_alarms({"alarms": {"diagnostics": {"rules": [{"match": "x"}, {"warn": "info"}]}}})
    with pytest.raises(ConfigError, match=r"alarms.diagnostics.stale_s"):
        parse_alarms({"alarms": {"diagnostics": {"stale_s": 0}}})
    assert INFO == 0


def state(**kw) -> DriverState:
    base = dict(connected=True, controller="10.0.0.5", robot_mode="RUNNING", safety_mode="NORMAL", speed_scaling=1.0,
                program_running=True, motion="idle", motion_group="arm", motion_target="", progress=0.0, message="")
    return DriverState(**{**base, **kw})


def test_the_robot_driver_reports_its_link_modes_and_joint_state_rate() -> None:
    ok = driver_diagnostic("/manual", "arm", state(), 124.0, 125.0)
    assert (ok.name, ok.level, ok.message) == ("manual: arm controller", OK, "connected")
    assert dict(ok.values)["joint states (Hz)"] == "124.0" and dict(ok.values)["controller"] == "10.0.0.5"
    lost = driver_diagnostic("/manual", "arm", state(connected=False, message="no data for 1 s"), 0.0, 125.0)
    assert (lost.level, lost.message) == (D_ERROR, "no data for 1 s")
    slow = driver_diagnostic("/manual", "arm", state(), 40.0, 125.0)
    assert (slow.level, slow.message) == (WARN, "joint states at 40 Hz (expected 125)")
    stop = driver_diagnostic("/manual", "arm", state(safety_mode="PROTECTIVE_STOP"), 125.0, 125.0)
    assert (stop.level, stop.message) == (WARN, "safety mode PROTECTIVE_STOP")
    m = RateMeter(window_s=2.0)
    for i in range(500):
        m.tick(i / 125)
    assert m.rate(499 / 125) == pytest.approx(125, abs=1) and m.rate(100.0) == 0


def test_the_demo_modules_report_their_verdicts() -> None:
    assert vision_diagnostic("ok", 0.5, 0.2, "/t").level == OK
    dark = vision_diagnostic("dark", 0.05, 0.2, "/t")
    assert (dark.name, dark.level, dark.message) == ("vision: camera brightness", WARN, "dark")
    assert dict(vision_diagnostic("no image", None, 9.0, "/t").values)["brightness"] == "-"
    assert load_diagnostic(0.3).level == OK and load_diagnostic(0.95).level == WARN
