"""The cell file's `manual:` section as the driver uses it (the BFF validates it against the JSON Schema at start;
this module only raises on what the driver cannot work with, naming the field)."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence, Union

# The UR joint names, in the controller's order (RTDE actual_q). A cell file's joint name ends with one of them
# (`shoulder_pan_joint`, `left_shoulder_pan_joint`): that gives its index; /joint_states carries the cell's names.
UR_JOINTS: tuple[str, ...] = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                              "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")
DEFAULT_HOST = "127.0.0.1"
UR_RTDE, ROS_CONTROL = "ur_rtde", "ros_control"
DRIVERS = (UR_RTDE, ROS_CONTROL)
ROS_NAME = re.compile(r"/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*")
LINK_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
# A group name is part of its topics' names (/cell/manual/<group>/state): a ROS name segment.
GROUP_NAME = re.compile(r"[a-z][a-z0-9_]*")
# manual.groups[].host and UR_HOSTS: an IPv4 address or a host name (its last label not all digits); the same
# pattern as config/features/manual.schema.json.
HOST = re.compile(r"(?:((25[0-5]|2[0-4][0-9]|1[0-9][0-9]|[1-9]?[0-9])\.){3}(25[0-5]|2[0-4][0-9]|1[0-9][0-9]|[1-9]?[0-9])"
                  r"|(?=.{1,253}$)([A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?\.)*(?![0-9]+$)"
                  r"[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)")


class ConfigError(ValueError):
    """The manual section cannot drive the robot (names the field: `manual.groups[0].joints[2]: ...`)."""


@dataclass(frozen=True)
class Group:
    name: str
    joints: tuple[str, ...]                        # the cell file's names (each ends with a UR joint name)
    indices: tuple[int, ...]                       # each joint's index in the robot's joint vector
    configurations: dict[str, tuple[float, ...]] = field(default_factory=dict)
    host: Optional[str] = None                     # manual.groups[].host; None: UR_HOST (see resolve_hosts)
    driver: str = UR_RTDE                          # the motion backend: ur_rtde or ros_control
    ros_control: Optional["RosControlSpec"] = None  # the arm's own driver's interfaces (driver ros_control)

    @property
    def arm_key(self) -> Optional[str]:
        """What makes two groups one arm, for the backends that do not go by host (ros_control: the controller)."""
        return f"ros_control:{self.ros_control.controller}" if self.ros_control is not None else None


@dataclass(frozen=True)
class RosControlSpec:
    """manual.groups[].ros_control: the standard interfaces of an arm's own ROS driver (docs/ros-interfaces.md)."""
    joint_states: str                              # sensor_msgs/JointState topic
    controller: str                                # joint_trajectory_controller namespace
    base_link: str
    tip_link: str
    robot_description: Optional[str] = None        # URDF parameter, or
    urdf: Optional[str] = None                     # a URDF file
    path_tolerance: float = 0.1                    # rad
    goal_time_tolerance: float = 1.0               # s
    outputs: dict[int, str] = field(default_factory=dict)   # digital output -> std_srvs/SetBool service
    inputs: dict[int, str] = field(default_factory=dict)    # digital input -> std_msgs/Bool topic

    @property
    def action(self) -> str:
        return f"{self.controller}/follow_joint_trajectory"

    @property
    def command(self) -> str:
        return f"{self.controller}/command"


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
    group: str = ""                 # the group whose controller's IO drives it (default: the first group)


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


def ur_joint_index(name: Any, robot_joints: Sequence[str] = UR_JOINTS) -> Optional[int]:
    """The index of the robot joint a cell file's joint name ends with (`left_elbow_joint` -> 2), else None."""
    if not isinstance(name, str):
        return None
    return next((i for i, j in enumerate(robot_joints) if name.endswith(j)), None)


def is_host(value: Any) -> bool:
    """An IPv4 address or a host name (the schema's rule for manual.groups[].host and UR_HOSTS)."""
    return isinstance(value, str) and HOST.fullmatch(value) is not None


def _ros_name(value: Any, where: str) -> str:
    if not isinstance(value, str) or not ROS_NAME.fullmatch(value):
        raise ConfigError(f"{where}: expected a ROS name like /joint_states, got {value!r}")
    return value


def _ros_control(raw: Any, where: str) -> RosControlSpec:
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: expected a mapping {{joint_states, controller, robot_description or urdf, "
                          f"base_link, tip_link}}")
    for key in ("base_link", "tip_link"):
        if not isinstance(raw.get(key), str) or not LINK_NAME.fullmatch(raw[key]):
            raise ConfigError(f"{where}.{key}: expected a URDF link name, got {raw.get(key)!r}")
    if (raw.get("robot_description") is None) == (raw.get("urdf") is None):
        raise ConfigError(f"{where}: give robot_description (a parameter) or urdf (a file), one of them")
    io = raw.get("io") or {}

    def wiring(kind: str) -> dict[int, str]:
        table = io.get(kind) or {}
        if not isinstance(table, dict):
            raise ConfigError(f"{where}.io.{kind}: expected a mapping of numbers 0..7 to ROS names")
        out: dict[int, str] = {}
        for k, v in table.items():
            n = _index(int(k) if isinstance(k, str) and k.isdigit() else k, f"{where}.io.{kind}.{k}")
            out[n] = _ros_name(v, f"{where}.io.{kind}.{k}")
        return out

    return RosControlSpec(
        joint_states=_ros_name(raw.get("joint_states", "/joint_states"), f"{where}.joint_states"),
        controller=_ros_name(raw.get("controller"), f"{where}.controller"),
        base_link=raw["base_link"], tip_link=raw["tip_link"],
        robot_description=None if raw.get("robot_description") is None
        else _ros_name(raw["robot_description"], f"{where}.robot_description"),
        urdf=None if raw.get("urdf") is None else str(raw["urdf"]),
        path_tolerance=_number(raw.get("path_tolerance", 0.1), f"{where}.path_tolerance"),
        goal_time_tolerance=_number(raw.get("goal_time_tolerance", 1.0), f"{where}.goal_time_tolerance",
                                    positive=False),
        outputs=wiring("outputs"), inputs=wiring("inputs"))


def parse_manual(section: Optional[Mapping[str, Any]], robot_joints: Sequence[str] = UR_JOINTS) -> ManualConfig:
    """Read the manual section; each group joint must name a robot joint (by its ending), once per group, and
    configurations must fit their group; a tool's group must be a group."""
    section = section or {}
    groups: dict[str, Group] = {}
    for i, g in enumerate(section.get("groups") or []):
        where = f"manual.groups[{i}]"
        if not isinstance(g, dict):
            raise ConfigError(f"{where}: expected a mapping {{name, joints, configurations, host}}")
        name = g.get("name")
        if not isinstance(name, str) or not GROUP_NAME.fullmatch(name):
            raise ConfigError(f"{where}.name: expected lower-case letters, digits and _ starting with a letter (it "
                              f"is part of the group's topic names), got {name!r}")
        if name in groups:
            raise ConfigError(f"{where}.name: {name!r} is used twice")
        host = g.get("host")
        if host is not None and not is_host(host):
            raise ConfigError(f"{where}.host: expected a host name or an IPv4 address, got {host!r}")
        joints = tuple(g.get("joints") or ())
        if not joints:
            raise ConfigError(f"{where}.joints: expected at least one joint")
        driver = g.get("driver", UR_RTDE)
        if driver not in DRIVERS:
            raise ConfigError(f"{where}.driver: expected one of {', '.join(DRIVERS)}, got {driver!r}")
        spec: Optional[RosControlSpec] = None
        indices: list[int] = []
        if driver == ROS_CONTROL:
            spec = _ros_control(g.get("ros_control"), f"{where}.ros_control")
            if host is not None:
                raise ConfigError(f"{where}.host: a ros_control group has no controller host (its driver owns it)")
            for k, j in enumerate(joints):
                if not isinstance(j, str) or not LINK_NAME.fullmatch(j):
                    raise ConfigError(f"{where}.joints[{k}]: expected a joint name, got {j!r}")
                if j in joints[:k]:
                    raise ConfigError(f"{where}.joints[{k}]: {j!r} is named twice")
            indices = list(range(len(joints)))
        elif g.get("ros_control") is not None:
            raise ConfigError(f"{where}.ros_control: only for driver: ros_control")
        for k, j in enumerate(joints if driver == UR_RTDE else ()):
            index = ur_joint_index(j, robot_joints)
            if index is None:
                raise ConfigError(f"{where}.joints[{k}]: {j!r} is not a joint of the robot (a joint name ends with "
                                  f"one of {', '.join(robot_joints)})")
            if index in indices:
                raise ConfigError(f"{where}.joints[{k}]: {j!r} is the same robot joint ({robot_joints[index]}) as "
                                  f"joints[{indices.index(index)}]")
            indices.append(index)
        configs: dict[str, tuple[float, ...]] = {}
        for cname, values in (g.get("configurations") or {}).items():
            if not isinstance(values, (list, tuple)) or len(values) != len(joints):
                count = len(values) if isinstance(values, (list, tuple)) else "no list of"
                raise ConfigError(f"{where}.configurations.{cname}: {count} values for {len(joints)} joints")
            configs[cname] = tuple(_number(v, f"{where}.configurations.{cname}", positive=False) for v in values)
        groups[name] = Group(name, joints, tuple(indices), configs, host, driver, spec)
    tools: dict[str, Tool] = {}
    first_group = next(iter(groups), "")
    for i, t in enumerate(section.get("tools") or []):
        if not isinstance(t, dict) or not isinstance(t.get("name"), str):
            raise ConfigError(f"manual.tools[{i}]: expected {{name, actions, group}}")
        group = t.get("group", first_group)
        if "group" in t and (not isinstance(group, str) or group not in groups):
            raise ConfigError(f"manual.tools[{i}].group: {group!r} is not a motion group (manual.groups: "
                              f"{', '.join(groups) or 'none'})")
        if not group:
            raise ConfigError(f"manual.tools[{i}]: a tool needs a motion group (manual.groups is empty)")
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
        if t["name"] in tools:
            raise ConfigError(f"manual.tools[{i}].name: {t['name']!r} is used twice")
        tools[t["name"]] = Tool(t["name"], actions, group)
    limits = {k: _number(section[k], f"manual.{k}") for k in
              ("default_speed", "default_acceleration", "max_speed", "max_acceleration", "max_tcp_speed",
               "max_tcp_acceleration") if section.get(k) is not None}
    return ManualConfig(groups, tools, limits)


# ---------------------------------------------------------------------------------------------- hosts and arms
def default_host(environ: Mapping[str, str]) -> str:
    return str(environ.get("UR_HOST") or "").strip() or DEFAULT_HOST


def resolve_hosts(section: Optional[Mapping[str, Any]], environ: Mapping[str, str]) -> dict[str, str]:
    """{group: the address of the UR controller that moves it}, in the cell file's group order (ur_rtde groups only).

    A group's `host`, else UR_HOST (else 127.0.0.1); UR_HOSTS (`<group>=<host>[,<group>=<host>...]`) overrides it
    per group, so several stacks of one cell run side by side. Groups with the same host belong to the same arm.
    Raises ConfigError for a malformed UR_HOSTS, one naming a group the cell does not have, or a bad host.
    (The BFF's bff/src/core/config/hosts.js resolveHosts is the same rule in JavaScript.)"""
    section = section or {}
    fallback = default_host(environ)
    hosts: dict[str, str] = {}
    for i, g in enumerate(section.get("groups") or []):
        if not isinstance(g, Mapping) or not isinstance(g.get("name"), str):
            continue
        if g.get("driver") == ROS_CONTROL:
            continue  # its own ROS driver owns its controller: no UR host
        host = g.get("host")
        if host is not None and not is_host(host):
            raise ConfigError(f"manual.groups[{i}].host: expected a host name or an IPv4 address, got {host!r}")
        hosts[g["name"]] = host if host is not None else fallback
    if not is_host(fallback) and any(h == fallback for h in hosts.values()):
        raise ConfigError(f"UR_HOST: expected a host name or an IPv4 address, got {fallback!r}")
    for entry in str(environ.get("UR_HOSTS") or "").split(","):
        entry = entry.strip()
        if not entry:
            continue
        group, sep, host = (x.strip() for x in entry.partition("="))
        if not sep or not group or not host:
            raise ConfigError(f"UR_HOSTS: expected <group>=<host>[,<group>=<host>...], got {entry!r}")
        if group not in hosts:
            raise ConfigError(f"UR_HOSTS: {group!r} is not a motion group of this cell (manual.groups: "
                              f"{', '.join(hosts) or 'none'})")
        if not is_host(host):
            raise ConfigError(f"UR_HOSTS: {group}={host}: expected a host name or an IPv4 address")
        hosts[group] = host
    return hosts


@dataclass(frozen=True)
class Arm:
    """One UR controller (one driver instance): the groups whose resolved host is `host`, and their tools."""
    host: str
    groups: tuple[str, ...]
    tools: tuple[str, ...]
    joint_names: tuple[str, ...]    # /joint_states names, one per robot joint in UR order (ros_control: the group's)
    driver: str = UR_RTDE
    ros_control: Optional[RosControlSpec] = None

    def config(self, cell: ManualConfig) -> ManualConfig:
        """The part of the cell's manual section this arm's driver works with."""
        return ManualConfig({g: cell.groups[g] for g in self.groups}, {t: cell.tools[t] for t in self.tools},
                            cell.limits)


def plan_arms(config: ManualConfig, hosts: Mapping[str, str],
              robot_joints: Sequence[str] = UR_JOINTS) -> list[Arm]:
    """Group the motion groups by their resolved host (first appearance first). Each arm's /joint_states names
    are its groups' joint names; a robot joint that no group names gets the arm's prefix (the part of its first
    joint name before the UR name; "" in the demo cell) + the UR name. Raises ConfigError when groups of one arm
    name one joint differently, when two arms would publish a joint under the same name, or when a tool's
    move_named step moves a group of another arm."""
    by_host: dict[str, list[str]] = {}
    order = list(config.groups)
    arms: list[Arm] = []
    owner: dict[str, tuple[str, str]] = {}          # joint name -> (host, group), over every arm
    for name, g in config.groups.items():
        if g.ros_control is None:
            by_host.setdefault(hosts.get(name) or DEFAULT_HOST, []).append(name)
            continue
        # A ros_control arm is its controller; its joints are the names its own driver publishes.
        key = g.arm_key or ""
        if any(a.host == key for a in arms):
            raise ConfigError(f"manual.groups[{order.index(name)}].ros_control.controller: {g.ros_control.controller} "
                              f"moves another group already (one motion group per trajectory controller)")
        for k, joint in enumerate(g.joints):
            if joint in owner:
                raise ConfigError(f"manual.groups[{order.index(name)}].joints[{k}]: {joint!r} is also a joint of "
                                  f"group {owner[joint][1]}")
            owner[joint] = (key, name)
        arms.append(Arm(key, (name,), tuple(t.name for t in config.tools.values() if t.group == name), g.joints,
                        ROS_CONTROL, g.ros_control))
    for host, names in by_host.items():
        named: dict[int, tuple[str, str]] = {}     # robot joint index -> (name, group)
        for gname in names:
            g = config.groups[gname]
            for k, (joint, index) in enumerate(zip(g.joints, g.indices)):
                if index in named and named[index][0] != joint:
                    raise ConfigError(
                        f"manual.groups[{order.index(gname)}].joints[{k}]: {joint!r} is robot joint "
                        f"{robot_joints[index]} of the arm at {host}, which group {named[index][1]} calls "
                        f"{named[index][0]!r}: groups of one arm name its joints alike")
                named.setdefault(index, (joint, gname))
        first = config.groups[names[0]]
        prefix = first.joints[0][:len(first.joints[0]) - len(robot_joints[first.indices[0]])]
        joint_names = tuple(named[i][0] if i in named else prefix + j for i, j in enumerate(robot_joints))
        # The names the groups give first, then the ones made up for joints no group names.
        for i in sorted(range(len(joint_names)), key=lambda k: k not in named):
            joint = joint_names[i]
            if joint in owner and owner[joint][0] != host:
                other_host, other_group = owner[joint]
                if i in named:
                    raise ConfigError(
                        f"manual.groups[{order.index(named[i][1])}]: joint name {joint!r} is also a joint of the arm "
                        f"at {other_host} (group {other_group}): /joint_states would mix the two arms; give each "
                        f"arm's joints their own prefix (left_shoulder_pan_joint, right_shoulder_pan_joint, ...)")
                raise ConfigError(
                    f"manual.groups[{order.index(names[0])}]: robot joint {robot_joints[i]} of the arm at {host} is in "
                    f"none of its groups and would be published as {joint!r}, a joint of the arm at {other_host} "
                    f"(group {other_group}): give each arm's joints their own prefix")
            owner.setdefault(joint, (host, named[i][1] if i in named else names[0]))
        tools = tuple(t.name for t in config.tools.values() if t.group in names)
        for ti, t in enumerate(config.tools.values()):
            if t.name not in tools:
                continue
            for a_i, action in enumerate(t.actions.values()):
                for n, step in enumerate(action.steps):
                    if isinstance(step, MoveNamedStep) and step.group not in names:
                        raise ConfigError(
                            f"manual.tools[{ti}].actions[{a_i}].steps[{n}]: group {step.group!r} is moved by the "
                            f"controller at {hosts.get(step.group)}, not by the tool's ({t.group}) at {host}")
        arms.append(Arm(host, tuple(names), tools, joint_names))
    return arms
