"""The cell file's `process:` section: the operations and their steps, pose tables, defaults.

The BFF validates the file against config/features/process.schema.json at start; this parser checks again what the
executor relies on (and what a schema cannot: named configurations, tools and pose tables that must exist), and
raises ConfigError naming the field: `process.operations[0].steps[2].move_pose: no pose table 'parts' (...)`.

Step syntax (one kind per step; every step may add `text:` to replace its generated text):
  { move_named: home, group?: arm, speed?: rad/s, acceleration?: rad/s^2 }          "Move to home"
  { move_relative: [dx, dy, dz, rx, ry, rz], frame?: base|tool, note?, speed?, ... }  "Move relative z +0.1 m"
  { move_pose: [x, y, z, rx, ry, rz], note?, ... }                                    "Move to pose (x .., y .., z ..)"
  { move_pose: <pose table>, offset?: [6 numbers], note?: approach, ... }             "Move to part 2 (approach)"
  { tool: gripper, action: close, group?: arm }                                       "Gripper close"
  { wait_s: 0.5 }                                                                     "Wait 0.5 s"
  { wait_topic: /x, field: data, equals|above|below: value, timeout_s?: 10 }          "Wait for /x data = true"
  { routine: <saved routine name> }                                                   "Run routine pick2"
A pose table's entry for cycle c is entry (c - 1) mod its length; its 1-based number shows in the text.
Move steps run on their `group` (default process.group); a tool step on its tool's group (manual.tools[].group: the
driver routes it there; a step's own `group:` must be that one). `start_configuration` is a configuration name of
process.group or a mapping {group: configuration}: at_start when every listed group is there.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence, Union

from cell_nodes.texts import english
from cell_nodes.manual.config import UR_JOINTS, ur_joint_index

DEFAULT_ACTION = "/cell/process/run"
DEFAULT_GROUP = "arm"
DEFAULT_START_TOLERANCE = 0.01    # rad, per joint: "the robot is at the start configuration"
DEFAULT_WAIT_TOPIC_TIMEOUT = 10.0  # s
DEFAULT_DRY_RUN_STEP_S = 0.3      # s per step in a dry run: slow enough for the page to follow
STEP_KINDS = ("move_named", "move_relative", "move_pose", "tool", "wait_s", "wait_topic", "routine")
CONDITIONS = ("equals", "above", "below")
FRAMES = ("base", "tool")


class ConfigError(ValueError):
    """The section cannot drive the process (names the field)."""


@dataclass(frozen=True)
class Motion:
    """What every move step has besides its target."""
    group: str
    speed: float            # 0: the section's default, then the driver's
    acceleration: float


@dataclass(frozen=True)
class MoveNamed:
    name: str
    motion: Motion
    text: str = ""


@dataclass(frozen=True)
class MoveRelative:
    offset: tuple[float, ...]
    frame: str
    motion: Motion
    note: str = ""
    text: str = ""


@dataclass(frozen=True)
class MovePose:
    pose: Optional[tuple[float, ...]]     # an absolute pose, or
    table: str                            # a pose table's name ("" with a literal pose)
    offset: Optional[tuple[float, ...]]   # added in the base frame (translation; rotation about the TCP)
    motion: Motion
    note: str = ""
    text: str = ""


@dataclass(frozen=True)
class Tool:
    tool: str
    action: str
    text: str = ""
    group: str = ""         # the tool's motion group (manual.tools[].group): the arm the driver runs it on


@dataclass(frozen=True)
class WaitTime:
    seconds: float
    text: str = ""


@dataclass(frozen=True)
class WaitTopic:
    topic: str
    field: str
    condition: str          # equals, above, below
    value: Any
    timeout_s: float
    text: str = ""


@dataclass(frozen=True)
class Routine:
    name: str
    text: str = ""


Step = Union[MoveNamed, MoveRelative, MovePose, Tool, WaitTime, WaitTopic, Routine]


@dataclass(frozen=True)
class Operation:
    name: str
    steps: tuple[Step, ...]


@dataclass(frozen=True)
class StatusField:
    label: str
    topic: str
    field: str = ""
    unit: str = ""


@dataclass(frozen=True)
class StartTarget:
    """One group of the start configuration: its configuration's joint values and their indices in the robot's
    joint vector (RobotState.joint_positions of /cell/manual/<group>/state)."""
    group: str
    configuration: str
    indices: tuple[int, ...] = ()   # empty when the cell has no manual section (at_start is then never true)
    joints: tuple[float, ...] = ()


@dataclass(frozen=True)
class ProcessConfig:
    operations: tuple[Operation, ...]
    action: str = DEFAULT_ACTION
    group: str = DEFAULT_GROUP
    poses: Mapping[str, tuple[tuple[float, ...], ...]] = field(default_factory=dict)
    start_configuration: str = ""   # as the state shows it: "home", or "left: home, right: home" for a mapping
    start_targets: tuple[StartTarget, ...] = ()   # every group listed, with its joint values (from manual:)
    start_tolerance: float = DEFAULT_START_TOLERANCE
    joint_speed: float = 0.0
    joint_acceleration: float = 0.0
    tcp_speed: float = 0.0
    tcp_acceleration: float = 0.0
    dry_run_step_s: float = DEFAULT_DRY_RUN_STEP_S
    status_fields: tuple[StatusField, ...] = ()

    @property
    def names(self) -> list[str]:
        return [o.name for o in self.operations]

    @property
    def start_groups(self) -> tuple[str, ...]:
        """The groups whose state topics at_start follows."""
        return tuple(t.group for t in self.start_targets)


# ------------------------------------------------------------------------------------------------ helpers
def _number(value: Any, where: str, minimum: Optional[float] = None, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(f"{where}: expected a number, got {value!r}")
    if positive and value <= 0:
        raise ConfigError(f"{where}: must be above 0, got {value!r}")
    if minimum is not None and value < minimum:
        raise ConfigError(f"{where}: must be at least {minimum:g}, got {value!r}")
    return float(value)


def _six(value: Any, where: str, what: str) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or len(value) != 6:
        raise ConfigError(f"{where}: expected {what} as 6 numbers [x, y, z (m), rx, ry, rz (rad)], got {value!r}")
    return tuple(_number(v, f"{where}[{i}]") for i, v in enumerate(value))


def _name(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"{where}: expected a name, got {value!r}")
    return value.strip()


def _shown(value: Any, where: str) -> str:
    """A text the page shows: a string, or one per language ({en: ..., es: ...}); the node keeps the English."""
    return _name(english(value), f"{where}.en" if isinstance(value, dict) else where)


def _text(raw: Mapping[str, Any], where: str, key: str = "text") -> str:
    """A step's `text` or `note`: a string, or one per language ({en: ..., es: ...}); the node keeps the English (the
    app says the others: the BFF gives it the cell file's texts)."""
    value = raw.get(key, "")
    if isinstance(value, dict):
        value = english(value)
        if not isinstance(value, str) or not value.strip():
            raise ConfigError(f"{where}.{key}.en: expected a text, got {value!r}")
    if not isinstance(value, str):
        raise ConfigError(f"{where}.{key}: expected a text, got {value!r}")
    return value.strip()


def _check_keys(raw: Mapping[str, Any], where: str, kind: str, allowed: Sequence[str]) -> None:
    extra = [k for k in raw if k not in allowed and k != kind]
    if extra:
        raise ConfigError(f"{where}: unknown key {extra[0]!r} for a {kind} step (it takes: {', '.join(allowed)})")


class _Manual:
    """What the driver offers (manual: section), to check step references; empty when the cell has none."""

    def __init__(self, section: Optional[Mapping[str, Any]]) -> None:
        self.present = bool(section)
        self.groups: dict[str, tuple[list[str], dict[str, list[float]]]] = {}
        self.tools: dict[str, list[str]] = {}
        self.tool_groups: dict[str, str] = {}
        for g in (section or {}).get("groups") or []:
            if isinstance(g, dict) and isinstance(g.get("name"), str):
                self.groups[g["name"]] = (list(g.get("joints") or []), dict(g.get("configurations") or {}))
        first = next(iter(self.groups), "")
        for t in (section or {}).get("tools") or []:
            if isinstance(t, dict) and isinstance(t.get("name"), str):
                self.tools[t["name"]] = [a.get("name") for a in t.get("actions") or [] if isinstance(a, dict)]
                self.tool_groups[t["name"]] = str(t.get("group") or first)

    def check_group(self, group: str, where: str) -> None:
        if self.present and group not in self.groups:
            raise ConfigError(f"{where}: unknown motion group {group!r} (the robot driver has: "
                              f"{', '.join(self.groups) or 'none'})")

    def check_configuration(self, group: str, name: str, where: str) -> None:
        if self.present and group in self.groups and name not in self.groups[group][1]:
            raise ConfigError(f"{where}: unknown configuration {name!r} for group {group} "
                              f"(it has: {', '.join(self.groups[group][1]) or 'none'})")

    def check_tool(self, tool: str, action: str, where: str) -> None:
        if not self.present:
            return
        if tool not in self.tools:
            raise ConfigError(f"{where}.tool: unknown tool {tool!r} (the robot driver has: "
                              f"{', '.join(self.tools) or 'none'})")
        if action not in self.tools[tool]:
            raise ConfigError(f"{where}.action: unknown action {action!r} for tool {tool} "
                              f"(it has: {', '.join(self.tools[tool]) or 'none'})")


ROBOT_JOINTS = UR_JOINTS


# ------------------------------------------------------------------------------------------------ steps
def _motion(raw: Mapping[str, Any], where: str, group: str, manual: _Manual) -> Motion:
    g = _name(raw["group"], f"{where}.group") if "group" in raw else group
    manual.check_group(g, f"{where}.group" if "group" in raw else where)
    speed = _number(raw["speed"], f"{where}.speed", positive=True) if "speed" in raw else 0.0
    acc = _number(raw["acceleration"], f"{where}.acceleration", positive=True) if "acceleration" in raw else 0.0
    return Motion(g, speed, acc)


MOTION_KEYS = ("group", "speed", "acceleration", "text")


def parse_step(raw: Any, where: str, group: str, poses: Mapping[str, Any], manual: _Manual) -> Step:
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: expected a step (a mapping with one of: {', '.join(STEP_KINDS)}), got {raw!r}")
    kinds = [k for k in STEP_KINDS if k in raw]
    if not kinds:
        raise ConfigError(f"{where}: unknown step {sorted(raw)!r} (a step has one of: {', '.join(STEP_KINDS)})")
    if len(kinds) > 1:
        raise ConfigError(f"{where}: one kind per step, got {' and '.join(kinds)}")
    kind = kinds[0]
    text = _text(raw, where)
    if kind == "move_named":
        _check_keys(raw, where, kind, MOTION_KEYS)
        motion = _motion(raw, where, group, manual)
        name = _name(raw["move_named"], f"{where}.move_named")
        manual.check_configuration(motion.group, name, f"{where}.move_named")
        return MoveNamed(name, motion, text)
    if kind == "move_relative":
        _check_keys(raw, where, kind, MOTION_KEYS + ("frame", "note"))
        frame = raw.get("frame", "base")
        if frame not in FRAMES:
            raise ConfigError(f"{where}.frame: expected base or tool, got {frame!r}")
        return MoveRelative(_six(raw["move_relative"], f"{where}.move_relative", "an offset"), frame,
                            _motion(raw, where, group, manual), _text(raw, where, "note"), text)
    if kind == "move_pose":
        _check_keys(raw, where, kind, MOTION_KEYS + ("offset", "note"))
        target = raw["move_pose"]
        offset = _six(raw["offset"], f"{where}.offset", "an offset") if "offset" in raw else None
        motion = _motion(raw, where, group, manual)
        note = _text(raw, where, "note")
        if isinstance(target, str):
            if target not in poses:
                raise ConfigError(f"{where}.move_pose: no pose table {target!r} (the section has: "
                                  f"{', '.join(poses) or 'none'})")
            return MovePose(None, target, offset, motion, note, text)
        return MovePose(_six(target, f"{where}.move_pose", "a pose (or the name of a pose table)"), "", offset,
                        motion, note, text)
    if kind == "tool":
        _check_keys(raw, where, kind, ("action", "group", "text"))
        tool = _name(raw["tool"], f"{where}.tool")
        action = _name(raw.get("action"), f"{where}.action")
        manual.check_tool(tool, action, where)
        own = manual.tool_groups.get(tool)
        if "group" in raw:
            g = _name(raw["group"], f"{where}.group")
            manual.check_group(g, f"{where}.group")
            if own and g != own:
                raise ConfigError(f"{where}.group: tool {tool} is on group {own} (manual.tools), not {g}")
        return Tool(tool, action, text, own or (_name(raw["group"], f"{where}.group") if "group" in raw else group))
    if kind == "wait_s":
        _check_keys(raw, where, kind, ("text",))
        return WaitTime(_number(raw["wait_s"], f"{where}.wait_s", minimum=0), text)
    if kind == "wait_topic":
        _check_keys(raw, where, kind, ("field", "timeout_s", "text") + CONDITIONS)
        topic = _name(raw["wait_topic"], f"{where}.wait_topic")
        if not topic.startswith("/"):
            raise ConfigError(f"{where}.wait_topic: expected a global topic name (/...), got {topic!r}")
        fld = _name(raw.get("field"), f"{where}.field")
        conds = [c for c in CONDITIONS if c in raw]
        if len(conds) != 1:
            raise ConfigError(f"{where}: a wait_topic step needs exactly one condition of: {', '.join(CONDITIONS)}")
        cond = conds[0]
        value = raw[cond]
        if cond in ("above", "below"):
            value = _number(value, f"{where}.{cond}")
        elif not isinstance(value, (bool, int, float, str)):
            raise ConfigError(f"{where}.equals: expected true/false, a number or a text, got {value!r}")
        timeout = _number(raw.get("timeout_s", DEFAULT_WAIT_TOPIC_TIMEOUT), f"{where}.timeout_s", positive=True)
        return WaitTopic(topic, fld, cond, value, timeout, text)
    _check_keys(raw, where, kind, ("text",))
    return Routine(_name(raw["routine"], f"{where}.routine"), text)


# ------------------------------------------------------------------------------------------------ section
def parse_process(section: Optional[Mapping[str, Any]], manual_section: Optional[Mapping[str, Any]] = None,
                  robot_joints: Sequence[str] = ROBOT_JOINTS) -> ProcessConfig:
    """Read the process section; references to the driver's groups, configurations and tools are checked against
    the manual section when the cell has one."""
    if section is None:
        raise ConfigError("process: the cell file has no process section")
    if not isinstance(section, dict):
        raise ConfigError(f"process: expected a mapping, got {section!r}")
    manual = _Manual(manual_section)
    action = _name(section.get("action", DEFAULT_ACTION), "process.action")
    if not action.startswith("/"):
        raise ConfigError(f"process.action: expected a global name (/...), got {action!r}")
    default_group = next(iter(manual.groups), DEFAULT_GROUP)
    group = _name(section["group"], "process.group") if "group" in section else default_group
    manual.check_group(group, "process.group")

    poses: dict[str, tuple[tuple[float, ...], ...]] = {}
    raw_poses = section.get("poses") or {}
    if not isinstance(raw_poses, dict):
        raise ConfigError("process.poses: expected a mapping of table name -> list of poses")
    for name, table in raw_poses.items():
        where = f"process.poses.{name}"
        if not isinstance(table, list) or not table:
            raise ConfigError(f"{where}: expected a non-empty list of poses [x, y, z, rx, ry, rz]")
        poses[str(name)] = tuple(_six(p, f"{where}[{i}]", "a pose") for i, p in enumerate(table))

    raw_ops = section.get("operations")
    if not isinstance(raw_ops, list) or not raw_ops:
        raise ConfigError("process.operations: expected a non-empty list of operations {name, steps}")
    operations: list[Operation] = []
    for i, op in enumerate(raw_ops):
        where = f"process.operations[{i}]"
        if not isinstance(op, dict):
            raise ConfigError(f"{where}: expected an operation {{name, steps}}, got {op!r}")
        # title: what the page shows (per language); the node and its log use the name.
        extra = [k for k in op if k not in ("name", "title", "steps")]
        if extra:
            raise ConfigError(f"{where}: unknown key {extra[0]!r} (an operation has: name, title, steps)")
        name = _name(op.get("name"), f"{where}.name")
        if name in (o.name for o in operations):
            raise ConfigError(f"{where}.name: {name!r} is used twice")
        steps = op.get("steps")
        if not isinstance(steps, list) or not steps:
            raise ConfigError(f"{where}.steps: expected a non-empty list of steps")
        operations.append(Operation(name, tuple(parse_step(s, f"{where}.steps[{k}]", group, poses, manual)
                                                for k, s in enumerate(steps))))

    start_text, targets = _start_configuration(section.get("start_configuration"), group, manual, robot_joints)

    fields: list[StatusField] = []
    for i, f in enumerate(section.get("status_fields") or []):
        where = f"process.status_fields[{i}]"
        if not isinstance(f, dict):
            raise ConfigError(f"{where}: expected {{label, topic, field, unit}}")
        fields.append(StatusField(_shown(f.get("label"), f"{where}.label"), _name(f.get("topic"), f"{where}.topic"),
                                  str(f.get("field") or ""), str(f.get("unit") or "")))

    def opt(key: str, positive: bool = True) -> float:
        return _number(section[key], f"process.{key}", positive=positive, minimum=0) if key in section else 0.0

    return ProcessConfig(
        operations=tuple(operations), action=action, group=group, poses=poses, start_configuration=start_text,
        start_targets=targets,
        start_tolerance=opt("start_tolerance") or DEFAULT_START_TOLERANCE,
        joint_speed=opt("joint_speed"), joint_acceleration=opt("joint_acceleration"), tcp_speed=opt("tcp_speed"),
        tcp_acceleration=opt("tcp_acceleration"),
        dry_run_step_s=opt("dry_run_step_s", positive=False) if "dry_run_step_s" in section
        else DEFAULT_DRY_RUN_STEP_S,
        status_fields=tuple(fields))


def _start_configuration(raw: Any, group: str, manual: _Manual,
                         robot_joints: Sequence[str]) -> tuple[str, tuple[StartTarget, ...]]:
    """`start_configuration`: a configuration name of process.group, or {group: configuration, ...}. Returns the
    text the state shows and one target per group."""
    if raw is None or raw == "":
        return "", ()
    where = "process.start_configuration"
    if isinstance(raw, Mapping):
        if not raw:
            raise ConfigError(f"{where}: expected a configuration name or a mapping {{group: configuration}} with "
                              f"at least one group")
        wanted = [(_name(g, where), _name(name, f"{where}.{g}"), f"{where}.{g}") for g, name in raw.items()]
        for g, _, at in wanted:
            manual.check_group(g, at)
    else:
        wanted = [(group, _name(raw, where), where)]
    targets = []
    for g, name, at in wanted:
        manual.check_configuration(g, name, at)
        indices: tuple[int, ...] = ()
        joints: tuple[float, ...] = ()
        if g in manual.groups:
            names, configs = manual.groups[g]
            found = [ur_joint_index(j, robot_joints) for j in names]
            values = configs.get(name) or []
            if names and all(i is not None for i in found) and len(values) == len(names):
                indices = tuple(i for i in found if i is not None)
                joints = tuple(float(v) for v in values)
        targets.append(StartTarget(g, name, indices, joints))
    text = targets[0].configuration if not isinstance(raw, Mapping) else \
        ", ".join(f"{t.group}: {t.configuration}" for t in targets)
    return text, tuple(targets)


def substitute_parameters(section: Any, values: Mapping[str, Any], where: str = "process") -> Any:
    """The section with every `{parameter: id, scale?: k}` replaced by the parameter's value times k (the cell's
    parameters CSV, read at start: cell_nodes.parameters.read_values). Raises ConfigError naming the field for an
    unknown or non-numeric parameter."""
    if isinstance(section, dict):
        if "parameter" in section and set(section) <= {"parameter", "scale"}:
            pid = section["parameter"]
            if pid not in values:
                known = ", ".join(sorted(values)) or "none"
                raise ConfigError(f"{where}.parameter: unknown parameter {pid!r} (the cell's parameters: {known})")
            value = values[pid]
            scale = section.get("scale", 1)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or isinstance(scale, bool) \
                    or not isinstance(scale, (int, float)):
                raise ConfigError(f"{where}: parameter {pid!r} is not a number ({value!r}) or scale is not a number")
            return float(value) * float(scale)
        return {k: substitute_parameters(v, values, f"{where}.{k}") for k, v in section.items()}
    if isinstance(section, list):
        return [substitute_parameters(v, values, f"{where}[{i}]") for i, v in enumerate(section)]
    return section


def parse_cell_process(cell: Mapping[str, Any], values: Optional[Mapping[str, Any]] = None) -> ProcessConfig:
    """The cell file's process with its parameter references resolved (values: the parameters CSV's, read by the
    caller at start; None reads them here)."""
    if values is None:
        from cell_nodes.parameters import read_values  # the parameters feature is optional for a cell
        try:
            values = read_values(dict(cell))
        except Exception:  # noqa: BLE001 - a bad parameters section is the parameters node's to report; a reference
            values = {}   # to it then fails here with the field named

    return parse_process(substitute_parameters(cell.get("process"), values), cell.get("manual"))
