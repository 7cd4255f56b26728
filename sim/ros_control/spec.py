"""The cell file's `simulation:` section of kind ros_control, and each simulated arm's ROS names.

```yaml
simulation:
  kind: ros_control
  arms:
    - group: arm                          # a motion group of manual.groups with `driver: ros_control`
      model: kuka_iiwa/model.urdf         # from pybullet_data
      rename: { lbr_iiwa_: iiwa_ }        # name prefix as the real driver publishes them
      base: [0.0, 0.0, 0.0, 0]
      start_joints: [...]                 # one per movable joint of the model (rad)
      tool: { kind: vacuum, length: 0.06, suction_output: 0, vacuum_input: 1 }
      rate_hz: 200                        # /joint_states
  parts, stations, views: as for the UR sim (sim/cell_file.py)
```
The ROS names (joint_states, controller, robot_description, tip_link, the IO topics) are the ones the robot driver
uses: the group's `manual.groups[].ros_control` section, so the two can never disagree. parts/stations/views and
each arm's group and base are checked by sim/cell_file.py's parser (the same rules as the UR world).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

from ..cell_file import CellFileError, parse_simulation
from ..scene import ArmSpec, VacuumSpec, WorldSpec
from .model import ArmModel, ModelError, load_model

KIND = "ros_control"
ARM_KEYS = ("group", "base", "model", "rename", "start_joints", "tool", "rate_hz")
TOOL_KEYS = ("kind", "length", "suction_output", "vacuum_input")
DEFAULT_MODEL = "kuka_iiwa/model.urdf"


@dataclass(frozen=True)
class RosNames:
    """Where the simulated driver speaks (manual.groups[].ros_control of the arm's group)."""
    joint_states: str
    controller: str             # <controller>/follow_joint_trajectory, <controller>/command
    robot_description: str      # parameter name
    base_link: str
    tip_link: str
    suction_service: str        # std_srvs/SetBool: io.outputs[suction_output]
    holding_topic: str          # std_msgs/Bool: io.inputs[vacuum_input]


@dataclass(frozen=True)
class RosControlArm:
    group: str
    model_name: str
    model: ArmModel
    rename: tuple[tuple[str, str], ...]
    base: tuple[float, float, float]
    yaw: float
    start_joints: tuple[float, ...]
    tool_length: float
    suction_output: int
    vacuum_input: int
    rate_hz: float
    ros: RosNames

    @property
    def rename_map(self) -> dict[str, str]:
        return dict(self.rename)


@dataclass(frozen=True)
class RosControlWorld(WorldSpec):
    """A WorldSpec (arms as generic vacuum arms for the device code) plus the ros_control arms themselves."""
    kind: str = KIND
    robots: tuple[RosControlArm, ...] = field(default_factory=tuple)

    def robot(self, group: str) -> RosControlArm:
        return next(r for r in self.robots if r.group == group)


def simulation_kind(doc: Any) -> Optional[str]:
    section = doc.get("simulation") if isinstance(doc, dict) else None
    return section.get("kind") if isinstance(section, dict) else None


def _key(mapping: dict, number: int) -> Any:
    """YAML mapping keys may be written 0 or "0"."""
    return mapping.get(number, mapping.get(str(number)))


def parse_ros_control(doc: dict, path: str = "<cell file>") -> RosControlWorld:
    def bad(where: str, what: str) -> CellFileError:
        return CellFileError(f"cell file {path}: {where}: {what}")

    section = doc["simulation"]
    arms_in = section.get("arms")
    if not isinstance(arms_in, list) or not arms_in:
        raise bad("simulation.arms", f"expected a list of at least one arm, got {arms_in!r}")
    # The shared parser checks group, base, parts, stations and views; it knows only the UR arm's keys.
    generic = {k: v for k, v in section.items() if k != "kind"}
    generic["arms"] = []
    for i, entry in enumerate(arms_in):
        if not isinstance(entry, dict):
            raise bad(f"simulation.arms[{i}]", f"expected a mapping, got {entry!r}")
        for k in entry:
            if k not in ARM_KEYS:
                raise bad(f"simulation.arms[{i}].{k}", f"unknown field (expected one of: {', '.join(ARM_KEYS)})")
        generic["arms"].append({k: v for k, v in entry.items() if k in ("group", "base")})
    world = parse_simulation({**doc, "simulation": generic}, path)

    groups = {g.get("name"): g for g in ((doc.get("manual") or {}).get("groups") or []) if isinstance(g, dict)}
    robots: list[RosControlArm] = []
    arms: list[ArmSpec] = []
    for i, (entry, arm) in enumerate(zip(arms_in, world.arms)):
        where = f"simulation.arms[{i}]"
        model_name = entry.get("model", DEFAULT_MODEL)
        if not isinstance(model_name, str):
            raise bad(f"{where}.model", f"expected a URDF path inside pybullet_data, got {model_name!r}")
        rename = entry.get("rename", {})
        if not isinstance(rename, dict) or not all(isinstance(k, str) and k and isinstance(v, str)
                                                   for k, v in rename.items()):
            raise bad(f"{where}.rename", f"expected a mapping of name parts to their replacement, got {rename!r}")
        try:
            model = load_model(model_name, rename)
        except ModelError as e:
            raise bad(f"{where}.model", str(e)) from None
        n = len(model.joints)
        start = entry.get("start_joints", [0.0] * n)
        if (not isinstance(start, list) or len(start) != n
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in start)):
            raise bad(f"{where}.start_joints", f"expected {n} joint positions (rad) for {model_name}, got {start!r}")
        for k, (v, j) in enumerate(zip(start, model.joints)):
            if not j.lower - 1e-9 <= v <= j.upper + 1e-9:
                raise bad(f"{where}.start_joints[{k}]", f"{v} is outside {j.name}'s limits "
                                                        f"[{j.lower:.4f}, {j.upper:.4f}]")
        tool = entry.get("tool", {"kind": "vacuum"})
        if not isinstance(tool, dict) or tool.get("kind") != "vacuum":
            raise bad(f"{where}.tool.kind", f"expected vacuum (the ros_control cell has a suction cup), "
                                            f"got {tool.get('kind') if isinstance(tool, dict) else tool!r}")
        for k in tool:
            if k not in TOOL_KEYS:
                raise bad(f"{where}.tool.{k}", f"unknown field (expected one of: {', '.join(TOOL_KEYS)})")
        length = tool.get("length", 0.06)
        if isinstance(length, bool) or not isinstance(length, (int, float)) or not 0.03 <= length <= 0.3:
            raise bad(f"{where}.tool.length", f"expected flange to cup face from 0.03 to 0.3 m, got {length!r}")
        numbers = {}
        for k, default in (("suction_output", 0), ("vacuum_input", 1)):
            v = tool.get(k, default)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise bad(f"{where}.tool.{k}", f"expected an IO number, got {v!r}")
            numbers[k] = v
        rate = entry.get("rate_hz", 200)
        if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not 10 <= rate <= 1000:
            raise bad(f"{where}.rate_hz", f"expected a /joint_states rate from 10 to 1000 Hz, got {rate!r}")
        ros = _ros_names(groups.get(arm.group), arm.group, model, numbers, bad)
        robots.append(RosControlArm(group=arm.group, model_name=model_name, model=model,
                                    rename=tuple(rename.items()), base=arm.base, yaw=arm.yaw,
                                    start_joints=tuple(float(v) for v in start), tool_length=float(length),
                                    suction_output=numbers["suction_output"], vacuum_input=numbers["vacuum_input"],
                                    rate_hz=float(rate), ros=ros))
        arms.append(ArmSpec(group=arm.group, base=arm.base, yaw=arm.yaw,
                            tool=VacuumSpec(suction_output=numbers["suction_output"],
                                            vacuum_input=numbers["vacuum_input"]),
                            start_joints=tuple(float(v) for v in start)))
    return RosControlWorld(arms=tuple(arms), parts=world.parts, stations=world.stations, views=world.views,
                           robots=tuple(robots))


def _ros_names(group: Optional[dict], name: str, model: ArmModel, io_numbers: dict, bad) -> RosNames:
    where = f"manual.groups[{name}]"
    if group is None:
        raise bad(f"{where}", "the simulated arm's motion group is missing from manual.groups")
    joints = group.get("joints")
    if joints is not None and (not isinstance(joints, list) or set(joints) != set(model.joint_names)):
        raise bad(f"{where}.joints", f"the simulated model's joints are {', '.join(model.joint_names)}; "
                                     f"got {joints!r} (check simulation rename)")
    rc = group.get("ros_control")
    if not isinstance(rc, dict):
        raise bad(f"{where}.ros_control", "required for a ros_control simulation (joint_states, controller, "
                                          "robot_description, io)")

    def topic(key: str, value: Any = None) -> str:
        value = rc.get(key) if value is None else value
        if not isinstance(value, str) or not value.startswith("/") or "//" in value or value.endswith("/"):
            raise bad(f"{where}.ros_control.{key}", f"expected a global ROS name like /iiwa/{key}, got {value!r}")
        return value

    base_link = rc.get("base_link", model.base_link)
    if base_link not in model.links:
        raise bad(f"{where}.ros_control.base_link", f"{base_link!r} is no link of the simulated model "
                                                    f"({', '.join(model.links)})")
    tip = rc.get("tip_link", f"{model.prefix}link_ee")
    if not isinstance(tip, str) or not tip or tip in model.links:
        raise bad(f"{where}.ros_control.tip_link", f"expected the name of the tool's link at the cup face (the sim "
                                                   f"adds it), got {tip!r}")
    io = rc.get("io") or {}
    outputs = io.get("outputs") or {} if isinstance(io, dict) else {}
    inputs = io.get("inputs") or {} if isinstance(io, dict) else {}
    out_n, in_n = io_numbers["suction_output"], io_numbers["vacuum_input"]
    suction, holding = _key(outputs, out_n), _key(inputs, in_n)
    if suction is None:
        raise bad(f"{where}.ros_control.io.outputs", f"no output {out_n} (the vacuum's, simulation tool.suction_output)")
    if holding is None:
        raise bad(f"{where}.ros_control.io.inputs", f"no input {in_n} (part held, simulation tool.vacuum_input)")
    return RosNames(joint_states=topic("joint_states"), controller=topic("controller"),
                    # A cell that reads its URDF from a file still gets the parameter a real driver sets.
                    robot_description=topic("robot_description", rc.get("robot_description", "/robot_description")),
                    base_link=base_link, tip_link=tip,
                    suction_service=topic(f"io.outputs.{out_n}", suction),
                    holding_topic=topic(f"io.inputs.{in_n}", holding))

