"""check-config's look at the ros_control groups (no ROS needed): each group against the URDF its arm's driver will
offer, when that can be known before start: a `urdf` file, or the simulated driver's (the sim stands for the real
one). A group pointing at a live `robot_description` parameter is checked by the driver when it connects (the page
and an alarm say what does not match)."""
from __future__ import annotations

import os
from typing import Any, Callable, Mapping, Optional

from ..config import ROS_CONTROL, ConfigError, RosControlSpec, parse_manual
from .arm import Unreachable, load_kinematics

# (cell, group name) -> the URDF the simulated driver publishes for it, or None when the sim does not drive it.
SimUrdf = Callable[[Mapping[str, Any], str], Optional[str]]


def _sim_urdf(cell: Mapping[str, Any], group: str) -> Optional[str]:
    """The robot_description the simulated driver publishes for the group's arm (sim/ros_control)."""
    from sim.ros_control.model import urdf_text
    from sim.ros_control.spec import parse_ros_control
    world = parse_ros_control(dict(cell))
    robot = next((r for r in world.robots if r.group == group), None)
    if robot is None:
        return None
    return urdf_text(robot.model, robot.rename_map, robot.ros.tip_link, robot.tool_length)


def check_ros_control(cell: Mapping[str, Any], path: str, sim_urdf: SimUrdf = _sim_urdf) -> list[str]:
    try:
        config = parse_manual(cell.get("manual"))
    except ConfigError:
        return []  # check_manual reports it
    simulated = (cell.get("robot") or {}).get("simulated") is not False and \
        (cell.get("simulation") or {}).get("kind") == ROS_CONTROL
    problems: list[str] = []
    for i, g in enumerate(config.groups.values()):
        spec: Optional[RosControlSpec] = g.ros_control
        if g.driver != ROS_CONTROL or spec is None:
            continue
        where = f"manual.groups[{i}]"
        if spec.urdf:
            file = spec.urdf if os.path.isabs(spec.urdf) else os.path.join(os.path.dirname(path), spec.urdf)
            try:
                with open(file, encoding="utf-8") as f:
                    urdf: Optional[str] = f.read()
            except OSError as e:
                problems.append(f"{where}.ros_control.urdf: cannot read {file}: {e.strerror}")
                continue
        elif simulated:
            try:
                urdf = sim_urdf(cell, g.name)
            except Exception:  # noqa: BLE001 - the sim's own check (check_sim) reports what it cannot build
                continue
        else:
            urdf = None
        if urdf is None:
            continue
        try:
            kin = load_kinematics(spec, g.joints, urdf)
        except Unreachable as e:
            field = ".joints" if "not the URDF's joints" in e.reason else ".ros_control"
            problems.append(f"{where}{field}: {e.reason}")
            continue
        index = {n: k for k, n in enumerate(kin.joint_names)}
        for name, values in g.configurations.items():
            for j, (joint, v) in enumerate(zip(g.joints, values)):
                lo, hi = kin.lower[index[joint]], kin.upper[index[joint]]
                if not lo <= v <= hi:
                    problems.append(f"{where}.configurations.{name}[{j}]: {v:g} rad is outside the limits of "
                                    f"{joint} [{lo:.3f}, {hi:.3f}]")
                    break
    return problems
