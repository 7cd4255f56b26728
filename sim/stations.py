"""The stations' geometry: the boxes each station of a WorldSpec is built of (pure: no physics, no ROS).

sim/world.py builds the physics bodies from these shapes and sim/markers.py publishes them as scene markers, so the
3D view and the physics can never disagree. A shape is one body: a base pose (world frame) and its boxes, each with
half extents and a pose in the body frame. Rotations are about the world z axis only (a station's yaw).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from .scene import StationSpec, WorldSpec, yaw_quaternion

POCKET_CLEARANCE = 0.008  # a pocket is this much wider than a part
FIXTURE_WALL = 0.01
FIXTURE_WALL_HEIGHT = 0.015
FIXTURE_PLATE = 0.006     # plate thickness: a part resting in a pocket has its bottom here
FIXTURE_RGBA = (0.6, 0.6, 0.65, 1)
STAND_RGBA = (0.45, 0.5, 0.55, 1)

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]


@dataclass(frozen=True)
class StationShape:
    name: str
    kind: str                                # stand or fixture
    base_pos: Vec3                           # the body's origin, world frame
    base_orn: Quat
    halves: tuple[Vec3, ...]                 # each box's half extents
    positions: tuple[Vec3, ...]              # each box's centre in the body frame
    orns: Optional[tuple[Quat, ...]]         # each box's orientation in the body frame (None: all identity)
    rgba: tuple[float, float, float, float]
    slots: tuple[tuple[float, float], ...]   # fixture: the pockets' centres (world x, y); a stand: none


@dataclass(frozen=True)
class Box:
    """One box in the world frame: what a CUBE marker shows."""
    name: str                                # the station's (or part's) name
    centre: Vec3
    size: Vec3                               # full extents (m)
    orientation: Quat                        # x, y, z, w
    rgba: tuple[float, float, float, float]


def station_shape(st: StationSpec, part_size: float) -> StationShape:
    if st.kind == "stand":
        return _stand(st)
    if isinstance(st.pockets, int):
        return _fixture_row(st, part_size)
    return _fixture_free(st, part_size)


def station_shapes(spec: WorldSpec) -> list[StationShape]:
    return [station_shape(st, spec.parts.size) for st in spec.stations]


def _stand(st: StationSpec) -> StationShape:
    """A box whose top is at the stand's height."""
    half = (st.size[0] / 2, st.size[1] / 2, st.height / 2)
    return StationShape(st.name, st.kind, (st.position[0], st.position[1], st.height / 2), yaw_quaternion(st.yaw),
                        (half,), ((0.0, 0.0, 0.0),), None, STAND_RGBA, ())


def _fixture_row(st: StationSpec, part_size: float) -> StationShape:
    """N pockets in a row along the station's y axis, centred on its position (the demo's fixture)."""
    n = st.pockets
    pocket = part_size + POCKET_CLEARANCE
    wall = FIXTURE_WALL
    h = FIXTURE_WALL_HEIGHT
    halves, positions = [], []
    halves.append((0.1, (n * pocket + (n + 1) * wall) / 2, 0.003))
    positions.append((0, 0, 0.003))
    span = n * pocket + (n + 1) * wall
    for sx in (-1, 1):  # long walls
        halves.append((wall / 2, span / 2, h / 2))
        positions.append((sx * (pocket / 2 + wall / 2), 0, 0.006 + h / 2))
    for k in range(n + 1):  # cross walls between pockets
        y = -span / 2 + wall / 2 + k * (pocket + wall)
        halves.append((pocket / 2 + wall, wall / 2, h / 2))
        positions.append((0, y, 0.006 + h / 2))
    px, py = st.position
    if st.yaw == 0.0:
        slots = [(px, py - span / 2 + wall + pocket / 2 + k * (pocket + wall)) for k in range(n)]
    else:
        c, s = math.cos(st.yaw), math.sin(st.yaw)
        local = [-span / 2 + wall + pocket / 2 + k * (pocket + wall) for k in range(n)]
        slots = [(px - s * ly, py + c * ly) for ly in local]
    return StationShape(st.name, st.kind, (px, py, 0), yaw_quaternion(st.yaw), tuple(halves), tuple(positions), None,
                        FIXTURE_RGBA, tuple(slots))


def _fixture_free(st: StationSpec, part_size: float) -> StationShape:
    """One walled pocket at each given world position (turned by the station's yaw) on a common plate."""
    pocket = part_size + POCKET_CLEARANCE
    wall, h = FIXTURE_WALL, FIXTURE_WALL_HEIGHT
    pts = np.array(st.pockets, dtype=float)
    centre = (pts.min(axis=0) + pts.max(axis=0)) / 2
    reach = pocket / 2 + wall + 0.01
    plate_half = tuple((pts.max(axis=0) - pts.min(axis=0)) / 2 + reach)
    halves = [(plate_half[0], plate_half[1], FIXTURE_PLATE / 2)]
    positions = [(0.0, 0.0, FIXTURE_PLATE / 2)]
    orns = [(0.0, 0.0, 0.0, 1.0)]
    c, s = math.cos(st.yaw), math.sin(st.yaw)
    q = yaw_quaternion(st.yaw)
    for x, y in pts - centre:
        for lx, ly, hx, hy in ((pocket / 2 + wall / 2, 0, wall / 2, pocket / 2 + wall),
                               (-pocket / 2 - wall / 2, 0, wall / 2, pocket / 2 + wall),
                               (0, pocket / 2 + wall / 2, pocket / 2, wall / 2),
                               (0, -pocket / 2 - wall / 2, pocket / 2, wall / 2)):
            halves.append((hx, hy, h / 2))
            positions.append((x + c * lx - s * ly, y + s * lx + c * ly, FIXTURE_PLATE + h / 2))
            orns.append(q)
    return StationShape(st.name, st.kind, (float(centre[0]), float(centre[1]), 0), (0.0, 0.0, 0.0, 1.0),
                        tuple(halves), tuple(positions), tuple(orns), FIXTURE_RGBA,
                        tuple((float(x), float(y)) for x, y in pts))


# ---- world-frame boxes (for the scene markers) -------------------------------------------------------------------
def _quat_mul(a: Sequence[float], b: Sequence[float]) -> Quat:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def _rotate(q: Sequence[float], v: Sequence[float]) -> Vec3:
    x, y, z, w = q
    vx, vy, vz = v
    # v' = v + 2w (u x v) + 2 u x (u x v), u = (x, y, z)
    cx, cy, cz = y * vz - z * vy, z * vx - x * vz, x * vy - y * vx
    ccx, ccy, ccz = y * cz - z * cy, z * cx - x * cz, x * cy - y * cx
    return (vx + 2 * (w * cx + ccx), vy + 2 * (w * cy + ccy), vz + 2 * (w * cz + ccz))


def shape_boxes(shape: StationShape) -> list[Box]:
    """The shape's boxes in the world frame."""
    out = []
    for k, (half, pos) in enumerate(zip(shape.halves, shape.positions)):
        local = shape.orns[k] if shape.orns is not None else (0.0, 0.0, 0.0, 1.0)
        off = _rotate(shape.base_orn, pos)
        centre = tuple(float(b + o) for b, o in zip(shape.base_pos, off))
        orn = tuple(float(v) for v in _quat_mul(shape.base_orn, local))
        out.append(Box(shape.name, centre, tuple(float(2 * h) for h in half), orn, shape.rgba))  # type: ignore[arg-type]
    return out


def station_boxes(spec: WorldSpec) -> list[Box]:
    """Every station's boxes in the world frame, station by station (the cell file's order)."""
    return [b for shape in station_shapes(spec) for b in shape_boxes(shape)]
