"""The cell file's `recorder:` section for the recorder node: how long, how much, which topics (by default the
ones an engineer needs to see what led to an alarm, taken from the rest of the cell file)."""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from typing import Any, List, Mapping

from .core import RecorderConfig

SUBDIR = "recordings"
MB = 1024 * 1024
SEVERITIES = {"warning": 1, "error": 2}
ROSOUT = "/rosout_agg"
ALARMS = "/cell/alarms/list"
_TOPIC = re.compile(r"/[A-Za-z][\w/]*", re.ASCII)


class RecorderConfigError(ValueError):
    """A `recorder:` section the node cannot use; the message names the field."""


@dataclass(frozen=True)
class RecorderSetup:
    config: RecorderConfig
    topics: List[str]            # what is recorded (the alarms topic always: it says why a recording was made)
    alarms_topic: str


def default_topics(cell: Mapping[str, Any]) -> List[str]:
    """Joint states, each motion group's robot state, the process state and log, the alarms, the operation mode,
    every WrenchStamped sensor and the ROS log, as far as the cell file has them."""
    groups = (cell.get("manual") or {}).get("groups") or []
    out: List[str] = []
    for g in groups:
        rc = (g.get("ros_control") or {}) if g.get("driver") == "ros_control" else {}
        out.append(rc.get("joint_states") or "/joint_states")
        out.append(f"/cell/manual/{g.get('name')}/state")
    if "process" in cell:
        out += ["/cell/process/state", "/cell/process/log"]
    out.append(ALARMS)
    out.append((cell.get("operation_mode") or {}).get("topic") or "/cell/mode")
    out += [s["topic"] for s in cell.get("sensors") or [] if s.get("type") == "geometry_msgs/WrenchStamped"]
    out.append(ROSOUT)
    return list(dict.fromkeys(out))


def parse_recorder(cell: Mapping[str, Any], environ: Mapping[str, str] = os.environ) -> RecorderSetup:
    section = cell.get("recorder")
    if not isinstance(section, dict):
        raise RecorderConfigError(f"recorder: expected a mapping, got {section!r}")

    def number(key: str, default: float, minimum: float, maximum: float) -> float:
        v = section.get(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not minimum <= v <= maximum:
            raise RecorderConfigError(f"recorder.{key}: expected a number from {minimum:g} to {maximum:g}, got {v!r}")
        return float(v)

    severity = section.get("severity", "error")
    if severity not in SEVERITIES:
        raise RecorderConfigError(f"recorder.severity: expected one of {', '.join(SEVERITIES)}, got {severity!r}")
    topics = section.get("topics")
    if topics is None:
        topics = default_topics(cell)
    elif not isinstance(topics, list) or not all(isinstance(t, str) and _TOPIC.fullmatch(t) for t in topics):
        raise RecorderConfigError(f"recorder.topics: expected a list of global ROS names, got {topics!r}")
    decimate = section.get("decimate_s", {})
    if not isinstance(decimate, dict) or not all(
            isinstance(t, str) and _TOPIC.fullmatch(t) and not isinstance(v, bool) and isinstance(v, (int, float))
            and math.isfinite(v) and 0 < v <= 3600 for t, v in decimate.items()):
        raise RecorderConfigError(f"recorder.decimate_s: expected global ROS names mapped to seconds (0 to 3600), "
                                  f"got {decimate!r}")
    directory = section.get("directory")
    if directory is None:
        data_dir = environ.get("DATA_DIR")
        if not data_dir:
            raise RecorderConfigError("recorder: no directory for the recordings: set DATA_DIR (or recorder.directory)")
        directory = os.path.join(data_dir, SUBDIR)
    elif not isinstance(directory, str) or not directory.startswith("/"):
        raise RecorderConfigError(f"recorder.directory: expected an absolute path, got {directory!r}")
    config = RecorderConfig(
        directory=os.path.abspath(str(directory)),
        before_s=number("before_s", 120, 1, 3600),
        after_s=number("after_s", 10, 0, 600),
        max_bytes=int(number("memory_mb", 64, 1, 4096) * MB),
        max_count=int(number("keep_count", 20, 1, 10_000)),
        max_total_bytes=int(number("keep_mb", 1024, 1, 1_000_000) * MB),
        min_severity=SEVERITIES[severity],
        decimate_s={t: float(v) for t, v in decimate.items()},
    )
    # A decimated topic is recorded whether or not `topics` names it (a camera at one frame a second).
    return RecorderSetup(config, list(dict.fromkeys([*topics, *decimate, ALARMS])), ALARMS)
