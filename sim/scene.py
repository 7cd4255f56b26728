"""What the sim builds: the arms (base pose, tool), the parts, the stations and the extra camera viewpoints.

A WorldSpec comes from the cell file's optional `simulation:` section (parsed in sim/cell_file.py, documented in
docs/sim.md). Without that section the sim builds DEFAULT_WORLD, the demo cell's world: one arm at the origin with
the two-finger gripper (DO0 closes, DI1 closed, DI2 part), three cubes in a jittered row and a three-pocket fixture.
The demo's taught poses depend on that world, so its values here must not change.

Units inside: metres and radians (the cell file gives angles in degrees; the parser converts them).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Union

DOOR_INPUT = 0  # standard digital input 0 of every arm's controller: the cell door's safeguard circuit (closed = 1)


@dataclass(frozen=True)
class GripperSpec:
    """The two-finger gripper: a digital output closes it; inputs report closed and a part between the fingers."""
    kind: str = "gripper"
    close_output: int = 0
    closed_input: int = 1
    part_input: int = 2


@dataclass(frozen=True)
class VacuumSpec:
    """A suction cup: a digital output switches the vacuum; an input reads true while a part is held."""
    kind: str = "vacuum"
    suction_output: int = 0
    vacuum_input: int = 1


ToolSpec = Union[GripperSpec, VacuumSpec]


@dataclass(frozen=True)
class ArmSpec:
    group: str = "arm"
    base: tuple[float, float, float] = (0.0, 0.0, 0.0)   # world position of the robot base (m)
    yaw: float = 0.0                                      # base rotation about the world z axis (rad)
    tool: ToolSpec = field(default_factory=GripperSpec)
    start_joints: Optional[tuple[float, ...]] = None      # joint positions at start (rad); None: the demo's home

    @property
    def at_origin(self) -> bool:
        """The base frame is the world frame: readings need no transform (the demo world)."""
        return self.base == (0.0, 0.0, 0.0) and self.yaw == 0.0


@dataclass(frozen=True)
class PartsSpec:
    """Cubes: explicit `positions` (x, y, yaw), or `count` of them in a row from `start` by `step`.

    `jitter` (x, y in m, yaw in rad) adds uniform noise from the seed, drawn per part in the order x, y, yaw.
    """
    size: float = 0.04
    mass: float = 0.1
    positions: Optional[tuple[tuple[float, float, float], ...]] = None
    count: int = 3
    start: tuple[float, float] = (-0.45, -0.25)
    step: tuple[float, float] = (0.0, 0.12)
    jitter: tuple[float, float, float] = (0.03, 0.02, 0.3)

    @property
    def number(self) -> int:
        return len(self.positions) if self.positions is not None else self.count


# Part i's colour is PART_COLORS[i % len(PART_COLORS)] (rendered and in the scene markers alike).
PART_COLORS = [(0.85, 0.15, 0.15, 1), (0.15, 0.7, 0.2, 1), (0.2, 0.3, 0.9, 1), (0.9, 0.75, 0.1, 1),
               (0.6, 0.2, 0.7, 1), (0.1, 0.7, 0.75, 1)]


@dataclass(frozen=True)
class StationSpec:
    """A flat `stand` (a box whose top is at `height`) or a `fixture` (a plate with walled pockets).

    Fixture pockets: `pockets` = N builds a row of N pockets along the station's own y axis centred on `position`
    (the demo's fixture); a tuple of (x, y) builds one walled pocket at each world position on a common plate.
    """
    name: str = "fixture"
    kind: str = "fixture"
    position: tuple[float, float] = (-0.35, 0.35)
    yaw: float = 0.0
    size: tuple[float, float] = (0.1, 0.1)   # stand top (m)
    height: float = 0.1                       # stand top above the table (m)
    pockets: Union[int, tuple[tuple[float, float], ...]] = 3


@dataclass(frozen=True)
class ViewSpec:
    name: str
    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    fov: float = 60.0


@dataclass(frozen=True)
class WorldSpec:
    arms: tuple[ArmSpec, ...] = (ArmSpec(),)
    parts: PartsSpec = PartsSpec()
    stations: tuple[StationSpec, ...] = (StationSpec(),)
    views: tuple[ViewSpec, ...] = ()         # besides the built-in viewpoints (sim/cameras.py VIEWS)

    def arm(self, group: str) -> ArmSpec:
        for a in self.arms:
            if a.group == group:
                return a
        raise KeyError(group)


DEFAULT_WORLD = WorldSpec()


def default_world(group: str = "arm") -> WorldSpec:
    """The demo world with its arm standing for `group` (the cell's first motion group)."""
    return WorldSpec(arms=(ArmSpec(group=group),))


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    if yaw == 0.0:
        return (0.0, 0.0, 0.0, 1.0)
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
