"""The cell file's `alarms:` section as the alarms node uses it (the BFF validates it against the JSON Schema at
start; this module only raises on what the node cannot work with, naming the field)."""
from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass
from typing import Any, Mapping, Optional

from .table import ERROR, INFO, WARNING

SEVERITIES = {"info": INFO, "warning": WARNING, "error": ERROR}
WRENCH_TYPE = "geometry_msgs/WrenchStamped"


@dataclass(frozen=True)
class DiagRule:
    """Which diagnostics statuses raise alarms (name glob) and how severe, per level (None: no alarm)."""
    match: str
    warn: Optional[int] = WARNING
    error: Optional[int] = ERROR
    stale: Optional[int] = WARNING


class ConfigError(ValueError):
    """The alarms section cannot be used (names the field: `alarms.force_limit_n: ...`)."""


def default_robot_state_topic(group: str) -> str:
    """The robot driver's state topic of a motion group."""
    return f"/cell/manual/{group}/state"


@dataclass(frozen=True)
class AlarmsConfig:
    # (motion group, its cell_msgs/RobotState topic): every manual.groups entry, /cell/manual/<group>/state unless
    # robot_state_topics names another topic for it.
    robot_state_topics: tuple[tuple[str, str], ...] = ()
    fault_topics: tuple[str, ...] = ("/sim/faults",)
    wrench_topics: tuple[str, ...] = ()
    force_limit_n: Optional[float] = None       # None: no force supervision
    force_clear_n: Optional[float] = None       # the alarm clears below this (default 90 % of the limit)
    modules_topic: str = "/cell/modules/state"
    timeout_s: float = 2.0                      # a source that published and then fell silent this long: alarm
    robot_expected: bool = False                # the cell has a robot driver (a `manual:` section)
    startup_grace_s: float = 10.0               # an expected driver that never published by then: alarm
    severity: tuple[tuple[str, int], ...] = ()  # (alarm id glob, severity), first match wins
    alarm_mode: str = ""                        # "" : never touch the operation mode
    modes: tuple[str, ...] = ()                 # the cell's operation modes (a remembered mode must be one of them)
    mode_topic: str = "/cell/mode"
    set_mode_service: str = "/cell/set_mode"
    publish_period_s: float = 1.0
    diagnostics_topic: Optional[str] = None       # diagnostic_msgs/DiagnosticArray; None: no diagnostics alarms
    diagnostics_stale_s: float = 5.0
    diagnostics_rules: tuple[DiagRule, ...] = ()  # first match wins; a status no rule matches raises nothing

    @property
    def robot_groups(self) -> tuple[str, ...]:
        return tuple(g for g, _ in self.robot_state_topics)

    def severity_for(self, alarm_id: str, default: int) -> int:
        for pattern, sev in self.severity:
            if fnmatch.fnmatchcase(alarm_id, pattern):
                return sev
        return default

    @property
    def force_clear(self) -> Optional[float]:
        if self.force_limit_n is None:
            return None
        return self.force_clear_n if self.force_clear_n is not None else 0.9 * self.force_limit_n


def _number(value: Any, where: str, minimum: float = 0.0, strict: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(f"{where}: expected a number, got {value!r}")
    if value < minimum or (strict and value == minimum):
        raise ConfigError(f"{where}: must be {'above' if strict else 'at least'} {minimum:g}, got {value!r}")
    return float(value)


def _topic(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value.startswith("/"):
        raise ConfigError(f"{where}: expected a ROS name starting with '/', got {value!r}")
    return value


def _topics(value: Any, where: str) -> tuple[str, ...]:
    if not isinstance(value, list):
        raise ConfigError(f"{where}: expected a list of topics, got {value!r}")
    return tuple(_topic(t, f"{where}[{i}]") for i, t in enumerate(value))


def parse_alarms(cell: Mapping[str, Any]) -> AlarmsConfig:
    """The whole cell file in, the node's configuration out."""
    section = cell.get("alarms")
    if section is None:
        section = {}
    if not isinstance(section, Mapping):
        raise ConfigError(f"alarms: expected a mapping, got {section!r}")
    kw: dict[str, Any] = {}
    manual = cell.get("manual") if isinstance(cell.get("manual"), Mapping) else {}
    groups = [g["name"] for g in manual.get("groups") or [] if isinstance(g, Mapping) and isinstance(g.get("name"), str)]
    overrides_topics = section.get("robot_state_topics") or {}
    if not isinstance(overrides_topics, Mapping):
        raise ConfigError(f"alarms.robot_state_topics: expected a mapping of motion group to topic, got "
                          f"{overrides_topics!r}")
    for group in overrides_topics:
        if group not in groups:
            raise ConfigError(f"alarms.robot_state_topics.{group}: not a motion group of the robot driver "
                              f"(manual.groups: {', '.join(groups) or 'none'})")
    kw["robot_state_topics"] = tuple(
        (g, _topic(overrides_topics[g], f"alarms.robot_state_topics.{g}") if g in overrides_topics
         else default_robot_state_topic(g)) for g in groups)
    if "modules_topic" in section:
        kw["modules_topic"] = _topic(section["modules_topic"], "alarms.modules_topic")
    if "fault_topics" in section:
        kw["fault_topics"] = _topics(section["fault_topics"], "alarms.fault_topics")
    if "wrench_topics" in section:
        kw["wrench_topics"] = _topics(section["wrench_topics"], "alarms.wrench_topics")
    else:  # the cell's wrist F/T sensors
        sensors = cell.get("sensors") or []
        kw["wrench_topics"] = tuple(dict.fromkeys(
            s["topic"] for s in sensors if isinstance(s, Mapping) and s.get("type") == WRENCH_TYPE
            and isinstance(s.get("topic"), str)))
    if section.get("force_limit_n") is not None:
        kw["force_limit_n"] = _number(section["force_limit_n"], "alarms.force_limit_n")
        if section.get("force_clear_n") is not None:
            clear = _number(section["force_clear_n"], "alarms.force_clear_n")
            if clear > kw["force_limit_n"]:
                raise ConfigError(f"alarms.force_clear_n: must not be above force_limit_n "
                                  f"({kw['force_limit_n']:g}), got {clear:g}")
            kw["force_clear_n"] = clear
    elif section.get("force_clear_n") is not None:
        raise ConfigError("alarms.force_clear_n: needs force_limit_n")
    if "timeout_s" in section:
        kw["timeout_s"] = _number(section["timeout_s"], "alarms.timeout_s", strict=False)
    kw["robot_expected"] = cell.get("manual") is not None
    if "startup_grace_s" in section:
        kw["startup_grace_s"] = _number(section["startup_grace_s"], "alarms.startup_grace_s", strict=False)
    if "publish_period_s" in section:
        kw["publish_period_s"] = _number(section["publish_period_s"], "alarms.publish_period_s")
    overrides = section.get("severity") or {}
    if not isinstance(overrides, Mapping):
        raise ConfigError(f"alarms.severity: expected a mapping of alarm id to info/warning/error, got {overrides!r}")
    sev: list[tuple[str, int]] = []
    for pattern, name in overrides.items():
        if name not in SEVERITIES:
            raise ConfigError(f"alarms.severity.{pattern}: expected one of info, warning, error, got {name!r}")
        sev.append((str(pattern), SEVERITIES[name]))
    # Exact ids before globs, so `robot.*: warning` and `robot.emergency_stop: error` mean what they say.
    sev.sort(key=lambda p: any(ch in p[0] for ch in "*?["))
    kw["severity"] = tuple(sev)

    if section.get("diagnostics") is not None:
        kw.update(_diagnostics(section["diagnostics"]))

    mode = cell.get("operation_mode") or {}
    wanted = section.get("alarm_mode", "alarm")
    if wanted is not None and not isinstance(wanted, str):
        raise ConfigError(f"alarms.alarm_mode: expected a mode name or \"\", got {wanted!r}")
    modes = mode.get("modes") or []
    kw["alarm_mode"] = wanted if wanted and wanted in modes else ""
    kw["modes"] = tuple(m for m in modes if isinstance(m, str))
    kw["mode_topic"] = mode.get("topic", "/cell/mode")
    kw["set_mode_service"] = mode.get("set_service", "/cell/set_mode")
    return AlarmsConfig(**kw)


def _diagnostics(d: Any) -> dict[str, Any]:
    where = "alarms.diagnostics"
    if not isinstance(d, Mapping):
        raise ConfigError(f"{where}: expected a mapping (topic, stale_s, rules), got {d!r}")
    rules_in = d.get("rules") or []
    if not isinstance(rules_in, list):
        raise ConfigError(f"{where}.rules: expected a list of rules, got {rules_in!r}")
    levels = {**SEVERITIES, "none": None}
    rules = []
    for i, r in enumerate(rules_in):
        if not isinstance(r, Mapping) or not isinstance(r.get("match"), str) or not r["match"]:
            raise ConfigError(f"{where}.rules[{i}].match: a rule needs a status name or glob, got {r!r}")
        kw: dict[str, Any] = {"match": r["match"]}
        for level in ("warn", "error", "stale"):
            if level in r:
                if r[level] not in levels:
                    raise ConfigError(f"{where}.rules[{i}].{level}: expected one of info, warning, error, none, "
                                      f"got {r[level]!r}")
                kw[level] = levels[r[level]]
        rules.append(DiagRule(**kw))
    return {"diagnostics_topic": _topic(d.get("topic", "/diagnostics"), f"{where}.topic"),
            "diagnostics_stale_s": _number(d.get("stale_s", 5.0), f"{where}.stale_s"),
            "diagnostics_rules": tuple(rules)}


def alarm_mode_problem(cell: Mapping[str, Any]) -> Optional[str]:
    """Why the node will not switch the operation mode, for its start-up log (None: it will)."""
    section = cell.get("alarms") or {}
    wanted = section.get("alarm_mode", "alarm") if isinstance(section, Mapping) else "alarm"
    if not wanted:
        return "alarms.alarm_mode is empty: the operation mode is left alone"
    modes = (cell.get("operation_mode") or {}).get("modes") or []
    if wanted not in modes:
        return f"operation_mode.modes has no {wanted!r}: the operation mode is left alone"
    return None
