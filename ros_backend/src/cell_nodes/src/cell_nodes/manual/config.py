"""The cell file's `manual:` section as the driver uses it (the BFF validates it against the JSON Schema at start;
this module only raises on what the driver cannot work with, naming the field)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence, Union

# The UR joint names, in the controller's order (RTDE actual_q). /joint_states uses them.
UR_JOINTS: tuple[str, ...] = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                              "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")


class ConfigError(ValueError):
    """The manual section cannot drive the robot (names the field: `manual.groups[0].joints[2]: ...`)."""


@dataclass(frozen=True)
class Group:
    name: str
    joints: tuple[str, ...]
    indices: tuple[int, ...]                       # each joint's index in the robot's joint vector
    configurations: dict[str, tuple[float, ...]] = field(default_factory=dict)


@dataclass(frozen=True)
class DigitalOut:
    output: int
    value: bool


@dataclass(frozen=True)
class Wait:
    seconds: float


@dataclass(frozen=True)
class WaitInput:
    input: int
    value: bool
    timeout_s: float


@dataclass(frozen=True)
class MoveNamedStep:
    configuration: str
    group: str


Step = Union[DigitalOut, Wait, WaitInput, MoveNamedStep]


@dataclass(frozen=True)
class ToolAction:
    name: str
    steps: tuple[Step, ...]


@dataclass(frozen=True)
class Tool:
    name: str
    actions: dict[str, ToolAction]


@dataclass(frozen=True)
class ManualConfig:
    groups: dict[str, Group]
    tools: dict[str, Tool]
    limits: Mapping[str, float]     # the raw numbers of the section (limits.Limits applies defaults and caps)


def _number(value: Any, where: str, positive: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(f"{where}: expected a number, got {value!r}")
    if positive and value <= 0:
        raise ConfigError(f"{where}: must be above 0, got {value!r}")
    return float(value)


def _index(value: Any, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 7:
        raise ConfigError(f"{where}: expected a standard digital IO number 0..7, got {value!r}")
    return value


def _step(raw: Any, where: str) -> Step:
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: expected a mapping")
    if "digital_out" in raw:
        if not isinstance(raw.get("value"), bool):
            raise ConfigError(f"{where}.value: expected true or false")
        return DigitalOut(_index(raw["digital_out"], f"{where}.digital_out"), raw["value"])
    if "wait_s" in raw:
        return Wait(_number(raw["wait_s"], f"{where}.wait_s", positive=False))
    if "wait_input" in raw:
        if not isinstance(raw.get("value"), bool):
            raise ConfigError(f"{where}.value: expected true or false")
        return WaitInput(_index(raw["wait_input"], f"{where}.wait_input"), raw["value"],
                         _number(raw.get("timeout_s", 5.0), f"{where}.timeout_s"))
    if "move_named" in raw:
        if not isinstance(raw["move_named"], str) or not isinstance(raw.get("group"), str):
            raise ConfigError(f"{where}: move_named needs a configuration name and a group")
        return MoveNamedStep(raw["move_named"], raw["group"])
    raise ConfigError(f"{where}: unknown step (digital_out, wait_s, wait_input or move_named)")


def parse_manual(section: Optional[Mapping[str, Any]], robot_joints: Sequence[str] = UR_JOINTS) -> ManualConfig:
    """Read the manual section; group joints must be robot joints and configurations must fit their group."""
    section = section or {}
    groups: dict[str, Group] = {}
    for i, g in enumerate(section.get("groups") or []):
        where = f"manual.groups[{i}]"
        joints = tuple(g.get("joints") or ())
        indices = []
        for k, j in enumerate(joints):
            if j not in robot_joints:
                raise ConfigError(f"{where}.joints[{k}]: {j!r} is not a joint of the robot ({', '.join(robot_joints)})")
            indices.append(list(robot_joints).index(j))
        configs: dict[str, tuple[float, ...]] = {}
        for name, values in (g.get("configurations") or {}).items():
            if len(values) != len(joints):
                raise ConfigError(f"{where}.configurations.{name}: {len(values)} values for {len(joints)} joints")
            configs[name] = tuple(_number(v, f"{where}.configurations.{name}", positive=False) for v in values)
        groups[g["name"]] = Group(g["name"], joints, tuple(indices), configs)
    tools: dict[str, Tool] = {}
    for i, t in enumerate(section.get("tools") or []):
        actions: dict[str, ToolAction] = {}
        for k, a in enumerate(t.get("actions") or []):
            where = f"manual.tools[{i}].actions[{k}]"
            if not isinstance(a, dict) or not isinstance(a.get("name"), str):
                raise ConfigError(f"{where}: expected {{name, steps}}")
            steps = tuple(_step(s, f"{where}.steps[{n}]") for n, s in enumerate(a.get("steps") or []))
            for n, s in enumerate(steps):
                if isinstance(s, MoveNamedStep) and (s.group not in groups
                                                     or s.configuration not in groups[s.group].configurations):
                    raise ConfigError(f"{where}.steps[{n}]: no configuration {s.configuration!r} in group {s.group!r}")
            actions[a["name"]] = ToolAction(a["name"], steps)
        tools[t["name"]] = Tool(t["name"], actions)
    limits = {k: _number(section[k], f"manual.{k}") for k in
              ("default_speed", "default_acceleration", "max_speed", "max_acceleration", "max_tcp_speed",
               "max_tcp_acceleration") if section.get(k) is not None}
    return ManualConfig(groups, tools, limits)
