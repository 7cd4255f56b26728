"""Which of the cell file's devices the sim stands in for, and on which topics.

The cell file (config/demo-cell.yaml by default) declares the topics the UI reads; the sim publishes its
simulated devices there instead of on names of its own, so a cell file with other topic names works unchanged:

- every `sensors:` entry of type geometry_msgs/WrenchStamped gets the wrist force/torque reading,
- every `sensors:` entry of type cell_msgs/Scatter gets the tactile pad,
- every `video.streams:` entry gets one camera on its `topic`, showing the viewpoint its `view` names
  (sim/cameras.py VIEWS); a stream without `view` gets viewpoint number i mod len(VIEWS), i = its position.

Other sensor types are not the sim's (nothing is published for them); a missing section means no such devices.
A file that cannot be read, or a section the sim cannot use, raises CellFileError with a readable message.
The BFF validates the whole file against the JSON Schema; this module only checks what the sim relies on.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Sequence

import yaml  # PyYAML: Debian's ROS packages bring it (python3-yaml)

from .cameras import VIEWS

REPO_ROOT = Path(__file__).resolve().parents[1]
WRENCH_TYPE = "geometry_msgs/WrenchStamped"
TACTILE_TYPE = "cell_msgs/Scatter"
# Topics the sim publishes whatever the cell says: a device declared there would clash with them. (/joint_states
# is not the sim's: the robot driver publishes it from RTDE, as it would for a real UR.)
RESERVED_TOPICS = ("/sim/faults",)
# What rospy accepts as a global name (rosgraph.names.is_legal_name, anchored): a bad one must not
# surface as a ValueError from rospy.Publisher deep inside the bridge.
_TOPIC = re.compile(r"/[A-Za-z][\w/]*", re.ASCII)


class CellFileError(Exception):
    """The cell file cannot be read, or a section the sim uses has the wrong shape."""


@dataclass(frozen=True)
class Stream:
    name: str
    topic: str
    view: str  # a key of VIEWS


@dataclass(frozen=True)
class CellDevices:
    path: Optional[str] = None
    wrench_topics: tuple[str, ...] = ()
    tactile_topics: tuple[str, ...] = ()
    streams: tuple[Stream, ...] = ()

    @property
    def views(self) -> list[str]:
        """The viewpoints some stream shows, in VIEWS order (only these are ever rendered)."""
        used = {s.view for s in self.streams}
        return [v for v in VIEWS if v in used]


def default_cell_path() -> str:
    """CELL_CONFIG, else config/demo-cell.yaml in this repository (like the BFF and the ROS nodes)."""
    return os.environ.get("CELL_CONFIG") or str(REPO_ROOT / "config" / "demo-cell.yaml")


def load_devices(path: Optional[str] = None) -> CellDevices:
    path = path or default_cell_path()
    try:
        with open(path, encoding="utf-8") as f:
            doc = yaml.safe_load(f)
    except yaml.YAMLError as e:
        # PyYAML's messages span lines (context, position, problem): keep the error one line.
        raise CellFileError(f"cannot read cell file {path}: not valid YAML: {' '.join(str(e).split())}") from None
    except (OSError, ValueError) as e:  # ValueError: bad UTF-8, or a value such as an impossible date
        raise CellFileError(f"cannot read cell file {path}: {e}") from None
    return devices_from(doc, path)


def devices_from(doc: Any, path: str = "<cell file>", views: Sequence[str] = tuple(VIEWS)) -> CellDevices:
    """The sim's devices declared in a parsed cell file."""
    if not isinstance(doc, dict):
        raise CellFileError(f"cannot read cell file {path}: not a cell file (expected a mapping at the top level)")

    def bad(where: str, what: str) -> CellFileError:
        return CellFileError(f"cell file {path}: {where}: {what}")

    def topic_of(entry: dict, where: str) -> str:
        topic = entry.get("topic")
        if not isinstance(topic, str) or not _TOPIC.fullmatch(topic) or "//" in topic:
            raise bad(f"{where}.topic", f"expected a global ROS topic name like /cell/wrench, got {topic!r}")
        return topic

    sensors = doc.get("sensors") or []
    if not isinstance(sensors, list):
        raise bad("sensors", "expected a list")
    by_type: dict[str, list[str]] = {WRENCH_TYPE: [], TACTILE_TYPE: []}
    for i, entry in enumerate(sensors):
        if not isinstance(entry, dict):
            raise bad(f"sensors[{i}]", "expected a mapping")
        mtype = entry.get("type")
        topics = by_type.get(mtype) if isinstance(mtype, str) else None
        if topics is None:
            continue  # a sensor the sim does not simulate
        topic = topic_of(entry, f"sensors[{i}]")
        if topic not in topics:  # two UI panels may show one topic: publish it once
            topics.append(topic)

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
        streams.append(Stream(name=name if isinstance(name, str) else topic, topic=topic, view=view))

    devices = CellDevices(path=path, wrench_topics=tuple(by_type[WRENCH_TYPE]),
                          tactile_topics=tuple(by_type[TACTILE_TYPE]), streams=tuple(streams))
    # One topic, one type: rospy refuses a second publisher of another type on a topic.
    seen: dict[str, str] = {t: "the sim itself" for t in RESERVED_TOPICS}
    for kind, topics in (("wrench sensor", devices.wrench_topics), ("tactile sensor", devices.tactile_topics),
                         ("video stream", [s.topic for s in devices.streams])):
        for topic in topics:
            if topic in seen:
                raise bad(kind, f"{topic} is already used by {seen[topic]}")
            seen[topic] = f"a {kind}"
    return devices
