"""Which of the cell file's devices the sim stands in for, and on which topics.

The cell file (config/demo-cell.yaml by default) declares the topics the UI reads; the sim publishes its
simulated devices there instead of on names of its own, so a cell file with other topic names works unchanged:

- every `sensors:` entry of type geometry_msgs/WrenchStamped gets the wrist force/torque reading (of the arm its
  `group` names; default the first arm),
- every `sensors:` entry of type cell_msgs/Scatter gets the tactile pad (of the first arm with a gripper),
- every `video.streams:` entry gets one camera on its `topic`, showing the viewpoint its `view` names
  (sim/cameras.py VIEWS, then the `simulation.views` of the cell); a stream without `view` gets viewpoint number
  i mod (number of viewpoints), i = its position.

The optional `scene:` section (the UI's 3D view of the cell) names what the sim publishes for it: `scene.markers`,
a visualization_msgs/MarkerArray topic with the parts and stations (sim/markers.py), and each `scene.arms[]` entry's
`robot_description` parameter, which the UR sim sets to the simulated arm's URDF with the joint names of its motion
group (parse_scene below; the ros_control sim's driver sets its group's own parameter).

The optional `simulation:` section describes the world (arms with their base and tool, parts, stations, extra
camera viewpoints: parse_simulation below, docs/sim.md); without it the sim builds the demo world (sim/scene.py).
Other sensor types are not the sim's (nothing is published for them); a missing section means no such devices.
A file that cannot be read, or a section the sim cannot use, raises CellFileError with a readable message.
The BFF validates the whole file against the JSON Schema; this module only checks what the sim relies on.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

import yaml  # PyYAML: Debian's ROS packages bring it (python3-yaml)

from .cameras import VIEWS
from .scene import (DOOR_INPUT, ArmSpec, GripperSpec, PartsSpec, StationSpec, VacuumSpec, ViewSpec, WorldSpec,
                    default_world)
from .urdf import ur_joint_names

REPO_ROOT = Path(__file__).resolve().parents[1]
WRENCH_TYPE = "geometry_msgs/WrenchStamped"
TACTILE_TYPE = "cell_msgs/Scatter"
# Topics the sim publishes whatever the cell says: a device declared there would clash with them. (/joint_states
# is not the sim's: the robot driver publishes it from RTDE, as it would for a real UR.)
RESERVED_TOPICS = ("/sim/faults", "/sim/objects")
# What rospy accepts as a global name (rosgraph.names.is_legal_name, anchored): a bad one must not
# surface as a ValueError from rospy.Publisher deep inside the bridge.
_TOPIC = re.compile(r"/[A-Za-z][\w/]*", re.ASCII)
_FRAME = re.compile(r"[A-Za-z_][\w/]*", re.ASCII)   # a TF frame id (tf2: no leading slash)


class CellFileError(Exception):
    """The cell file cannot be read, or a section the sim uses has the wrong shape."""


@dataclass(frozen=True)
class Stream:
    name: str
    topic: str
    view: str  # a key of VIEWS
    raw: bool = False                          # sensor_msgs/Image (rgb8) instead of CompressedImage
    size: Optional[tuple[int, int]] = None     # a raw stream's image size (`sim_size`); None: the camera size


@dataclass(frozen=True)
class SceneArm:
    """One `scene.arms[]` entry: a motion group the 3D view shows, the ROS parameter with its URDF, its base."""
    group: str
    robot_description: Optional[str] = None          # parameter name; None: the view takes the driver's own
    base: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)   # x, y, z (m), yaw (deg): where the view puts it
    base_frame: Optional[str] = None                 # its base's TF frame (the view places it from TF instead)


@dataclass(frozen=True)
class ArmDescription:
    """A robot_description parameter the UR sim sets: its arm's URDF (with its tool) under the joint names of the
    arm's motion group, the names the robot driver publishes on /joint_states (sim/urdf.py ur_joint_names)."""
    param: str
    group: str
    tool: str                                        # gripper or vacuum
    joint_names: tuple[str, ...]                     # the six arm joints, UR order


@dataclass(frozen=True)
class SceneSpec:
    markers: Optional[str] = None                    # visualization_msgs/MarkerArray topic (None: not published)
    fixed_frame: Optional[str] = None                # the TF frame the view draws in (None: the view reads no TF)
    arms: tuple[SceneArm, ...] = ()
    descriptions: tuple[ArmDescription, ...] = ()    # UR sim only: the parameters to set (a ros_control driver sets
    #                                                  its own, manual.groups[].ros_control.robot_description)
    warnings: tuple[str, ...] = ()                   # what would make the view disagree with the sim (logged)


@dataclass(frozen=True)
class CellDevices:
    path: Optional[str] = None
    wrench_topics: tuple[str, ...] = ()
    tactile_topics: tuple[str, ...] = ()
    streams: tuple[Stream, ...] = ()
    # The world the sim builds (the cell file's `simulation:` section; without it the demo world).
    world: WorldSpec = field(default_factory=default_world)
    # The arm (group) whose wrist F/T each wrench topic carries, parallel to wrench_topics.
    wrench_groups: tuple[str, ...] = ()
    # The cell file's `scene:` section (the 3D view): the markers topic, the URDF parameters.
    scene: SceneSpec = field(default_factory=SceneSpec)

    @property
    def all_views(self) -> list[str]:
        """Every viewpoint of this cell: the built-in ones (VIEWS order), then the cell's own."""
        return list(VIEWS) + [v.name for v in self.world.views]

    @property
    def views(self) -> list[str]:
        """The viewpoints some stream shows, in all_views order (only these are ever rendered)."""
        used = {s.view for s in self.streams}
        return [v for v in self.all_views if v in used]

    @property
    def tactile_group(self) -> Optional[str]:
        """The arm whose finger pad the tactile topics carry: the first arm with a gripper."""
        return next((a.group for a in self.world.arms if isinstance(a.tool, GripperSpec)), None)


def default_cell_path() -> str:
    """CELL_CONFIG, else config/demo-cell.yaml in this repository (like the BFF and the ROS nodes)."""
    return os.environ.get("CELL_CONFIG") or str(REPO_ROOT / "config" / "demo-cell.yaml")


def load_devices(path: Optional[str] = None) -> CellDevices:
    path = path or default_cell_path()
    return devices_from(read_cell_file(path), path)


def read_cell_file(path: str) -> Any:
    """The parsed YAML document (CellFileError when it cannot be read)."""
    try:
        with open(path, encoding="utf-8") as f:
            doc = yaml.safe_load(f)
    except yaml.YAMLError as e:
        # PyYAML's messages span lines (context, position, problem): keep the error one line.
        raise CellFileError(f"cannot read cell file {path}: not valid YAML: {' '.join(str(e).split())}") from None
    except (OSError, ValueError) as e:  # ValueError: bad UTF-8, or a value such as an impossible date
        raise CellFileError(f"cannot read cell file {path}: {e}") from None
    return doc


def devices_from(doc: Any, path: str = "<cell file>", views: Optional[Sequence[str]] = None) -> CellDevices:
    """The sim's devices (and its world) declared in a parsed cell file."""
    if not isinstance(doc, dict):
        raise CellFileError(f"cannot read cell file {path}: not a cell file (expected a mapping at the top level)")

    def bad(where: str, what: str) -> CellFileError:
        return CellFileError(f"cell file {path}: {where}: {what}")

    world = parse_simulation(doc, path)
    if views is None:
        views = tuple(VIEWS) + tuple(v.name for v in world.views)
    arm_groups = [a.group for a in world.arms]

    def topic_of(entry: dict, where: str) -> str:
        topic = entry.get("topic")
        if not isinstance(topic, str) or not _TOPIC.fullmatch(topic) or "//" in topic:
            raise bad(f"{where}.topic", f"expected a global ROS topic name like /cell/wrench, got {topic!r}")
        return topic

    sensors = doc.get("sensors") or []
    if not isinstance(sensors, list):
        raise bad("sensors", "expected a list")
    by_type: dict[str, list[str]] = {WRENCH_TYPE: [], TACTILE_TYPE: []}
    wrench_groups: list[str] = []
    has_gripper = any(isinstance(a.tool, GripperSpec) for a in world.arms)
    for i, entry in enumerate(sensors):
        if not isinstance(entry, dict):
            raise bad(f"sensors[{i}]", "expected a mapping")
        mtype = entry.get("type")
        topics = by_type.get(mtype) if isinstance(mtype, str) else None
        if topics is None:
            continue  # a sensor the sim does not simulate
        topic = topic_of(entry, f"sensors[{i}]")
        group = arm_groups[0]
        if mtype == WRENCH_TYPE and "group" in entry:
            group = entry["group"]
            if group not in arm_groups:
                raise bad(f"sensors[{i}].group", f"no simulated arm {group!r} (the sim's arms: {', '.join(arm_groups)})")
        if mtype == TACTILE_TYPE and not has_gripper:
            raise bad(f"sensors[{i}]", "a tactile pad needs an arm with a gripper (simulation.arms)")
        if topic in topics:  # two UI panels may show one topic: publish it once
            if mtype == WRENCH_TYPE and wrench_groups[topics.index(topic)] != group:
                raise bad(f"sensors[{i}].group", f"{topic} already carries the wrist F/T of arm "
                                                 f"{wrench_groups[topics.index(topic)]!r}")
            continue
        topics.append(topic)
        if mtype == WRENCH_TYPE:
            wrench_groups.append(group)

    video = doc.get("video") or {}
    if not isinstance(video, dict):
        raise bad("video", "expected a mapping")
    entries = video.get("streams") or []
    if not isinstance(entries, list):
        raise bad("video.streams", "expected a list")
    streams: list[Stream] = []
    for i, entry in enumerate(entries):
        where = f"video.streams[{i}]"
        if not isinstance(entry, dict):
            raise bad(where, "expected a mapping")
        topic = topic_of(entry, where)
        if any(s.topic == topic for s in streams):
            raise bad(f"{where}.topic", f"{topic} is already another stream's topic")
        view = entry.get("view", views[i % len(views)])
        if view not in views:
            raise bad(f"{where}.view", f"unknown viewpoint {view!r} (the sim has: {', '.join(views)})")
        name = entry.get("name")
        kind = entry.get("type", "compressed")
        if kind not in ("compressed", "raw"):
            raise bad(f"{where}.type", f"expected compressed or raw, not {kind!r}")
        size = entry.get("sim_size")
        if size is not None and not (isinstance(size, list) and len(size) == 2
                                     and all(isinstance(v, int) and 16 <= v <= 4096 for v in size)):
            raise bad(f"{where}.sim_size", "expected [width, height] in pixels (16..4096)")
        streams.append(Stream(name=name if isinstance(name, str) else topic, topic=topic, view=view,
                              raw=kind == "raw", size=tuple(size) if size else None))

    scene = parse_scene(doc, world, path)
    devices = CellDevices(path=path, wrench_topics=tuple(by_type[WRENCH_TYPE]),
                          tactile_topics=tuple(by_type[TACTILE_TYPE]), streams=tuple(streams), world=world,
                          wrench_groups=tuple(wrench_groups), scene=scene)
    # One topic, one type: rospy refuses a second publisher of another type on a topic.
    seen: dict[str, str] = {t: "the sim itself" for t in RESERVED_TOPICS}
    for kind, topics in (("wrench sensor", devices.wrench_topics), ("tactile sensor", devices.tactile_topics),
                         ("video stream", [s.topic for s in devices.streams]),
                         ("scene.markers", [scene.markers] if scene.markers else [])):
        for topic in topics:
            if topic in seen:
                raise bad(kind, f"{topic} is already used by {seen[topic]}")
            seen[topic] = f"a {kind}"
    return devices


# ---------------------------------------------------------------------------------------------- scene section
def parse_scene(doc: dict, world: WorldSpec, path: str = "<cell file>") -> SceneSpec:
    """The cell file's `scene:` section as far as the sim uses it (absent: nothing to publish). Only what the sim
    relies on is checked (the BFF validates the whole file against its schema): the markers topic and the parameter
    names are global ROS names, each group a motion group once, each base [x, y, z, yaw_deg]; a UR arm's group joints
    must name UR joints (they become the URDF's joint names)."""
    def bad(where: str, what: str) -> CellFileError:
        return CellFileError(f"cell file {path}: {where}: {what}")

    def ros_name(value: Any, where: str, example: str) -> str:
        if not isinstance(value, str) or not _TOPIC.fullmatch(value) or "//" in value or value.endswith("/"):
            raise bad(where, f"expected a global ROS name like {example}, got {value!r}")
        return value

    section = doc.get("scene")
    if section is None:
        return SceneSpec()
    if not isinstance(section, dict):
        raise bad("scene", f"expected a mapping, got {section!r}")
    markers = section.get("markers")
    if markers is not None:
        markers = ros_name(markers, "scene.markers", "/sim/parts")
    fixed_frame = section.get("fixed_frame")
    if fixed_frame is not None and (not isinstance(fixed_frame, str) or not _FRAME.fullmatch(fixed_frame)):
        raise bad("scene.fixed_frame", f"expected a TF frame name like world, got {fixed_frame!r}")
    manual = doc.get("manual")
    groups = {g.get("name"): g for g in (manual.get("groups") or []) if isinstance(g, dict)} \
        if isinstance(manual, dict) and isinstance(manual.get("groups"), list) else {}
    entries = section.get("arms") or []
    if not isinstance(entries, list):
        raise bad("scene.arms", f"expected a list, got {entries!r}")
    arms: list[SceneArm] = []
    for i, entry in enumerate(entries):
        where = f"scene.arms[{i}]"
        if not isinstance(entry, dict):
            raise bad(where, f"expected a mapping {{group, robot_description, base}}, got {entry!r}")
        group = entry.get("group")
        if not isinstance(group, str) or not group:
            raise bad(f"{where}.group", f"expected the name of a motion group, got {group!r}")
        if groups and group not in groups:
            raise bad(f"{where}.group", f"{group!r} is not a motion group of manual.groups ({', '.join(groups)})")
        if any(a.group == group for a in arms):
            raise bad(f"{where}.group", f"{group!r} is already another arm's group")
        param = entry.get("robot_description")
        if param is not None:
            param = ros_name(param, f"{where}.robot_description", "/robot_description")
            other = next((a.group for a in arms if a.robot_description == param), None)
            if other is not None:
                raise bad(f"{where}.robot_description", f"{param} is already the parameter of group {other!r}")
        base = entry.get("base", [0, 0, 0, 0])
        if (not isinstance(base, list) or len(base) != 4
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in base)):
            raise bad(f"{where}.base", f"expected [x, y, z, yaw_deg], got {base!r}")
        base_frame = entry.get("base_frame")
        if base_frame is not None:
            if not isinstance(base_frame, str) or not _FRAME.fullmatch(base_frame):
                raise bad(f"{where}.base_frame", f"expected a TF frame name like left_base_link, got {base_frame!r}")
            if fixed_frame is None:
                raise bad(f"{where}.base_frame", "needs scene.fixed_frame (the frame TF places the base in)")
        arms.append(SceneArm(group, param, tuple(float(v) for v in base), base_frame))  # type: ignore[arg-type]

    descriptions: list[ArmDescription] = []
    warnings: list[str] = []
    ros_control = {r.group: r for r in getattr(world, "robots", ())}   # sim/ros_control: its driver sets the param
    order = list(groups)
    for i, arm in enumerate(arms):
        where = f"scene.arms[{i}]"
        try:
            sim_arm = world.arm(arm.group)
        except KeyError:
            if arm.robot_description:
                warnings.append(f"{where}: group {arm.group!r} is no simulated arm (the sim's arms: "
                                f"{', '.join(a.group for a in world.arms)}): nothing sets {arm.robot_description}")
            continue
        x, y, z = sim_arm.base
        yaw_deg = math.degrees(sim_arm.yaw)
        bx, by, bz, byaw = arm.base
        turn = (byaw - yaw_deg + 180.0) % 360.0 - 180.0
        if arm.base_frame is None and (max(abs(bx - x), abs(by - y), abs(bz - z)) > 1e-6 or abs(turn) > 1e-6):
            warnings.append(f"{where}.base: {list(arm.base)} but the simulated arm stands at "
                            f"[{x:g}, {y:g}, {z:g}, {yaw_deg:g}] (simulation.arms): the 3D view would show it elsewhere")
        if arm.group in ros_control:
            driver_param = ros_control[arm.group].ros.robot_description
            if arm.robot_description and arm.robot_description != driver_param:
                warnings.append(f"{where}.robot_description: {arm.robot_description}, but the ros_control driver "
                                f"sets {driver_param} (manual.groups[].ros_control.robot_description)")
            continue
        if not arm.robot_description:
            continue
        joints = groups.get(arm.group, {}).get("joints") or []
        gwhere = f"manual.groups[{order.index(arm.group)}].joints" if arm.group in groups else where
        if not isinstance(joints, list):
            raise bad(gwhere, f"expected a list of joint names, got {joints!r}")
        try:
            names = ur_joint_names(joints)
        except ValueError as e:
            # The manual section's own check reports a bad joint name; here it only means no URDF is set.
            warnings.append(f"{gwhere}: {e}: nothing sets {arm.robot_description}")
            continue
        descriptions.append(ArmDescription(arm.robot_description, arm.group, sim_arm.tool.kind, tuple(names)))
    return SceneSpec(markers=markers, fixed_frame=fixed_frame, arms=tuple(arms), descriptions=tuple(descriptions),
                     warnings=tuple(warnings))


# ---------------------------------------------------------------------------------------------- simulation section
SIM_KEYS = ("arms", "parts", "stations", "views")
ARM_KEYS = ("group", "base", "tool", "start_joints")
GRIPPER_KEYS = ("kind", "close_output", "closed_input", "part_input")
VACUUM_KEYS = ("kind", "suction_output", "vacuum_input")
PARTS_KEYS = ("size", "mass", "positions", "count", "start", "step", "jitter")
STAND_KEYS = ("name", "kind", "position", "yaw_deg", "size", "height")
FIXTURE_KEYS = ("name", "kind", "position", "yaw_deg", "pockets")
VIEW_KEYS = ("eye", "target", "fov")
DIGITAL_OUTPUTS = range(0, 8)                      # standard digital outputs 0-7
TOOL_INPUTS = range(DOOR_INPUT + 1, 8)              # standard digital inputs 1-7 (DI0: the door)
MIN_BASE_DISTANCE = 0.2                             # m between two arms' bases (their base cylinders are 0.15 m wide)
_ID = re.compile(r"[a-z][a-z0-9_-]*")


def parse_simulation(doc: dict, path: str = "<cell file>") -> WorldSpec:
    """The cell file's `simulation:` section as a WorldSpec; absent: the demo world, its arm standing for the cell's
    first motion group. Errors (CellFileError) name the field, e.g. `simulation.arms[1].tool.kind: ...`."""
    manual = doc.get("manual")
    groups = [g.get("name") for g in (manual.get("groups") or []) if isinstance(g, dict)] \
        if isinstance(manual, dict) and isinstance(manual.get("groups"), list) else []
    groups = [g for g in groups if isinstance(g, str)]
    first = groups[0] if groups else "arm"
    section = doc.get("simulation")
    if section is None:
        return default_world(first)

    def bad(where: str, what: str) -> CellFileError:
        return CellFileError(f"cell file {path}: {where}: {what}")

    def mapping(value: Any, where: str, keys: Sequence[str]) -> dict:
        if not isinstance(value, dict):
            raise bad(where, f"expected a mapping, got {value!r}")
        for k in value:
            if k not in keys:
                raise bad(f"{where}.{k}", f"unknown field (expected one of: {', '.join(keys)})")
        return value

    def number(value: Any, where: str, lo: float = -math.inf, hi: float = math.inf, lo_open: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise bad(where, f"expected a number, got {value!r}")
        if value < lo or value > hi or (lo_open and value == lo):
            rng = f"{'>' if lo_open else '>='} {lo:g}" if hi == math.inf else f"from {lo:g} to {hi:g}"
            raise bad(where, f"expected a number {rng}, got {value!r}")
        return float(value)

    def numbers(value: Any, where: str, sizes: Sequence[int], what: str,
                check: Optional[Callable[[float, str], float]] = None) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) not in sizes:
            raise bad(where, f"expected {what}, got {value!r}")
        return tuple((check or number)(v, f"{where}[{k}]") for k, v in enumerate(value))

    def integer(value: Any, where: str, allowed: range) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value not in allowed:
            raise bad(where, f"expected an integer from {allowed.start} to {allowed.stop - 1}, got {value!r}")
        return value

    if isinstance(section, dict) and "kind" in section:
        # What the sim stands for: UR controllers (the default) or a ros_control robot driver (sim/ros_control).
        if section["kind"] == "ros_control":
            from .ros_control.spec import parse_ros_control
            return parse_ros_control(doc, path)
        if section["kind"] != "ur":
            raise bad("simulation.kind", f"expected ur or ros_control, got {section['kind']!r}")
        section = {k: v for k, v in section.items() if k != "kind"}
    mapping(section, "simulation", SIM_KEYS)

    # arms
    arms: list[ArmSpec] = []
    if "arms" in section:
        entries = section["arms"]
        if not isinstance(entries, list) or not entries:
            raise bad("simulation.arms", f"expected a list of at least one arm, got {entries!r}")
        for i, entry in enumerate(entries):
            where = f"simulation.arms[{i}]"
            mapping(entry, where, ARM_KEYS)
            group = entry.get("group")
            if not isinstance(group, str) or not group:
                raise bad(f"{where}.group", f"expected the name of a motion group, got {group!r}")
            if groups and group not in groups:
                raise bad(f"{where}.group", f"{group!r} is not a motion group of manual.groups ({', '.join(groups)})")
            if any(a.group == group for a in arms):
                raise bad(f"{where}.group", f"{group!r} is already another arm's group")
            base = numbers(entry.get("base", [0, 0, 0, 0]), f"{where}.base", (4,), "[x, y, z, yaw_deg]")
            for k, other in enumerate(arms):
                gap = math.dist(base[:2], other.base[:2])
                if gap < MIN_BASE_DISTANCE:
                    raise bad(f"{where}.base", f"{gap:.2f} m from the base of arms[{k}] (at least "
                                               f"{MIN_BASE_DISTANCE} m apart)")
            start = None
            if "start_joints" in entry:
                start = numbers(entry["start_joints"], f"{where}.start_joints", (6,), "6 joint positions (rad)",
                                lambda v, w: number(v, w, -2 * math.pi, 2 * math.pi))
            arms.append(ArmSpec(group=group, base=base[:3], yaw=math.radians(base[3]) if base[3] else 0.0,
                                tool=_tool(entry.get("tool", {"kind": "gripper"}), f"{where}.tool", mapping, integer,
                                           bad), start_joints=start))
    else:
        arms = list(default_world(first).arms)

    # parts
    parts = PartsSpec()
    if "parts" in section:
        where = "simulation.parts"
        entry = mapping(section["parts"], where, PARTS_KEYS)
        kw: dict[str, Any] = {}
        if "size" in entry:
            kw["size"] = number(entry["size"], f"{where}.size", 0.01, 0.1)
        if "mass" in entry:
            kw["mass"] = number(entry["mass"], f"{where}.mass", 0.0, 5.0, lo_open=True)
        if "positions" in entry:
            for k in ("count", "start", "step"):
                if k in entry:
                    raise bad(f"{where}.{k}", "give either positions or count/start/step, not both")
            pos = entry["positions"]
            if not isinstance(pos, list):
                raise bad(f"{where}.positions", f"expected a list of [x, y] or [x, y, yaw_deg], got {pos!r}")
            items = [numbers(v, f"{where}.positions[{k}]", (2, 3), "[x, y] or [x, y, yaw_deg]")
                     for k, v in enumerate(pos)]
            kw["positions"] = tuple((v[0], v[1], math.radians(v[2]) if len(v) == 3 else 0.0) for v in items)
            kw["jitter"] = (0.0, 0.0, 0.0)
        else:
            if "count" in entry:
                kw["count"] = integer(entry["count"], f"{where}.count", range(0, 21))
            if "start" in entry:
                kw["start"] = numbers(entry["start"], f"{where}.start", (2,), "[x, y]")
            if "step" in entry:
                kw["step"] = numbers(entry["step"], f"{where}.step", (2,), "[dx, dy]")
        if "jitter" in entry:
            j = numbers(entry["jitter"], f"{where}.jitter", (3,), "[x, y, yaw_deg]",
                        lambda v, w: number(v, w, 0.0))
            kw["jitter"] = (j[0], j[1], math.radians(j[2]))
        parts = PartsSpec(**kw)

    # stations
    stations: tuple[StationSpec, ...] = (StationSpec(),)
    if "stations" in section:
        entries = section["stations"]
        if not isinstance(entries, list):
            raise bad("simulation.stations", f"expected a list, got {entries!r}")
        out: list[StationSpec] = []
        for i, entry in enumerate(entries):
            where = f"simulation.stations[{i}]"
            kind = entry.get("kind") if isinstance(entry, dict) else None
            if kind not in ("stand", "fixture"):
                raise bad(f"{where}.kind", f"expected stand or fixture, got {kind!r}")
            mapping(entry, where, STAND_KEYS if kind == "stand" else FIXTURE_KEYS)
            name = entry.get("name")
            if not isinstance(name, str) or not _ID.fullmatch(name):
                raise bad(f"{where}.name", f"expected a name like hand_over (a-z, 0-9, _ or -), got {name!r}")
            if any(s.name == name for s in out):
                raise bad(f"{where}.name", f"{name!r} is already another station's name")
            kw = {"name": name, "kind": kind}
            if "yaw_deg" in entry:
                yaw = number(entry["yaw_deg"], f"{where}.yaw_deg", -360, 360)
                kw["yaw"] = math.radians(yaw) if yaw else 0.0
            pockets = entry.get("pockets", 3)
            if kind == "fixture" and isinstance(pockets, list):
                if "position" in entry:
                    raise bad(f"{where}.position", "a fixture with a list of pockets has them at world positions: "
                                                   "no position")
                if not pockets:
                    raise bad(f"{where}.pockets", "expected at least one pocket")
                kw["pockets"] = tuple(numbers(v, f"{where}.pockets[{k}]", (2,), "[x, y]")
                                      for k, v in enumerate(pockets))
                pitch = parts.size + 0.008 + 0.02
                for a in range(len(kw["pockets"])):
                    for b in range(a):
                        if math.dist(kw["pockets"][a], kw["pockets"][b]) < pitch - 1e-9:
                            raise bad(f"{where}.pockets[{a}]", f"overlaps pockets[{b}] (pocket centres at least "
                                                                f"{pitch:.3f} m apart for these parts)")
            else:
                if "position" not in entry:
                    raise bad(f"{where}.position", "required: [x, y]")
                kw["position"] = numbers(entry["position"], f"{where}.position", (2,), "[x, y]")
                if kind == "fixture":
                    kw["pockets"] = integer(pockets, f"{where}.pockets", range(1, 11)) if not isinstance(
                        pockets, list) else pockets
                else:
                    kw["size"] = numbers(entry.get("size", [0.1, 0.1]), f"{where}.size", (2,), "[x, y] (m)",
                                         lambda v, w: number(v, w, 0.02, 1.0))
                    kw["height"] = number(entry.get("height", 0.1), f"{where}.height", 0.01, 0.5)
            out.append(StationSpec(**kw))
        stations = tuple(out)

    # views
    views: list[ViewSpec] = []
    if "views" in section:
        entries = section["views"]
        if not isinstance(entries, dict):
            raise bad("simulation.views", f"expected a mapping of viewpoint names to {{eye, target, fov}}, "
                                          f"got {entries!r}")
        for name, entry in entries.items():
            where = f"simulation.views.{name}"
            if not isinstance(name, str) or not _ID.fullmatch(name):
                raise bad(where, "expected a viewpoint name like hand_over (a-z, 0-9, _ or -)")
            if name in VIEWS:
                raise bad(where, f"{name!r} is a built-in viewpoint (the sim has: {', '.join(VIEWS)})")
            mapping(entry, where, VIEW_KEYS)
            for k in ("eye", "target"):
                if k not in entry:
                    raise bad(f"{where}.{k}", "required: [x, y, z]")
            eye = numbers(entry["eye"], f"{where}.eye", (3,), "[x, y, z]")
            target = numbers(entry["target"], f"{where}.target", (3,), "[x, y, z]")
            if math.dist(eye, target) < 0.05:
                raise bad(f"{where}.target", "too close to the eye")
            fov = number(entry.get("fov", 60), f"{where}.fov", 10, 120)
            views.append(ViewSpec(name, eye, target, fov))  # type: ignore[arg-type]
    return WorldSpec(arms=tuple(arms), parts=parts, stations=stations, views=tuple(views))


def _tool(value: Any, where: str, mapping, integer, bad):
    kind = value.get("kind") if isinstance(value, dict) else None
    if kind not in ("gripper", "vacuum"):
        raise bad(f"{where}.kind", f"expected gripper or vacuum, got {kind!r}")
    if kind == "gripper":
        mapping(value, where, GRIPPER_KEYS)
        spec: Any = GripperSpec(close_output=integer(value.get("close_output", 0), f"{where}.close_output",
                                                     DIGITAL_OUTPUTS),
                                closed_input=integer(value.get("closed_input", 1), f"{where}.closed_input", TOOL_INPUTS),
                                part_input=integer(value.get("part_input", 2), f"{where}.part_input", TOOL_INPUTS))
        if spec.closed_input == spec.part_input:
            raise bad(f"{where}.part_input", f"DI{spec.part_input} is already the closed_input")
        return spec
    mapping(value, where, VACUUM_KEYS)
    return VacuumSpec(suction_output=integer(value.get("suction_output", 0), f"{where}.suction_output", DIGITAL_OUTPUTS),
                      vacuum_input=integer(value.get("vacuum_input", 1), f"{where}.vacuum_input", TOOL_INPUTS))
