"""The scene markers of the cell's 3D view: a visualization_msgs/MarkerArray with the parts and the stations.

Both sims publish it on the cell file's `scene.markers` topic, when there is one (sim/ros_bridge.py, at OBJECTS_RATE
with /sim/objects). Frame `world` (the table centre, z up, the table top at z = 0), whatever the arms' bases:
- ns `parts`: one CUBE per part, id = the part's index (creation order, as /sim/objects), its pose from the physics
  (a carried part moves with the tool), scale = the part's edge length, the colour the cameras show it in;
- ns `stations`: the boxes the stations are built of (sim/stations.py: a stand is one box; a fixture its plate and
  its pocket walls), ids 0.. station by station in the cell file's order, text = the station's name.
Every marker: action ADD, lifetime 0 (until replaced), so each message replaces the whole scene.
Building the message needs the message classes only (no node): pure, tested without ROS (sim/tests/test_scene.py).
"""
from __future__ import annotations

from typing import Any, Optional, Sequence

from .scene import PART_COLORS
from .stations import Box

FRAME = "world"
PARTS_NS = "parts"
STATIONS_NS = "stations"


def part_boxes(poses: Sequence[tuple[Sequence[float], Sequence[float]]], size: float,
               colors: Sequence[Sequence[float]] = PART_COLORS) -> list[Box]:
    """The parts as boxes: `poses` [(position, quaternion xyzw)] in the world frame (World.body_poses()), `size` the
    cubes' edge (PartsSpec.size); part i has colors[i mod len(colors)]."""
    return [Box("", tuple(float(v) for v in pos), (float(size),) * 3, tuple(float(v) for v in orn),  # type: ignore
                tuple(float(c) for c in colors[i % len(colors)]))
            for i, (pos, orn) in enumerate(poses)]


def _marker(box: Box, ns: str, marker_id: int, frame_id: str, stamp: Any, types: Any):
    m = types.Marker()
    m.header.frame_id = frame_id
    if stamp is not None:
        m.header.stamp = stamp
    m.ns, m.id, m.type, m.action = ns, marker_id, types.Marker.CUBE, types.Marker.ADD
    p, o = m.pose.position, m.pose.orientation
    p.x, p.y, p.z = box.centre
    o.x, o.y, o.z, o.w = box.orientation
    m.scale.x, m.scale.y, m.scale.z = box.size
    m.color.r, m.color.g, m.color.b, m.color.a = box.rgba
    m.text = box.name
    return m


class _Types:
    def __init__(self) -> None:
        from visualization_msgs.msg import Marker, MarkerArray
        self.Marker, self.MarkerArray = Marker, MarkerArray


def marker_array(parts: Sequence[Box], stations: Sequence[Box], stamp: Optional[Any] = None,
                 frame_id: str = FRAME):
    """The MarkerArray of the scene: `parts` (part_boxes) in ns `parts`, `stations` (sim.stations.station_boxes) in
    ns `stations`, ids by position in each list; `stamp`: every header's stamp (None: zero)."""
    types = _Types()
    out = types.MarkerArray()
    out.markers = ([_marker(b, PARTS_NS, i, frame_id, stamp, types) for i, b in enumerate(parts)]
                   + [_marker(b, STATIONS_NS, i, frame_id, stamp, types) for i, b in enumerate(stations)])
    return out
