"""What the recorder does, without ROS: keep every recorded topic's messages in the ring, and save a window of it
around each new error alarm (the `before` seconds up to the alarm and the `after` seconds that follow) or when
asked, as an MCAP file in the recordings directory kept within its retention limits."""
from __future__ import annotations

import os
import re
import threading
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Callable, Dict, Iterable, List, Mapping, Optional, Tuple

from . import retention
from .mcap_file import SUFFIX, write_mcap
from .ring import RawMessage, Ring
from .sidecar import describe, sidecar_path, write_sidecar
from .timeline import Timeline

S = 1_000_000_000
SLACK_S = 5.0


@dataclass(frozen=True)
class RecorderConfig:
    directory: str                      # where recordings go ($DATA_DIR/recordings)
    before_s: float = 120.0             # kept in memory: what a recording has before its alarm
    after_s: float = 10.0               # what it has after the alarm
    max_bytes: int = 64 * 1024 * 1024   # the ring's payload bound
    max_count: int = 20                 # recordings kept on disk
    max_total_bytes: int = 1024 * 1024 * 1024
    min_severity: int = 2               # cell_msgs/Alarm: 0 info, 1 warning, 2 error
    decimate_s: Mapping[str, float] = field(default_factory=dict)  # topic -> at most one message per this many s


@dataclass
class Pending:
    reason: str                         # "alarm <id>: <text>" or "saved by <user>"
    at_ns: int                          # the alarm's (or the request's) time
    alarms: List[str] = field(default_factory=list)

    def end_ns(self, after_s: float) -> int:
        return self.at_ns + int(after_s * S)


@dataclass(frozen=True)
class Saved:
    name: str
    path: str
    size: int
    reason: str
    messages: int
    start_ns: int
    end_ns: int
    deleted: Tuple[str, ...]            # older recordings retention removed to make room
    sidecar_error: str = ""             # why its JSON description was not written ("" it was)


def file_name(at_ns: int, reason: str) -> str:
    """`20261126T140512Z-alarm-robot-protective-stop.mcap`: sorts by time, says why, safe in any file system."""
    stamp = datetime.fromtimestamp(at_ns / S, tz=timezone.utc).strftime("%Y%m%dT%H%M%S") + f".{at_ns // 1_000_000 % 1000:03d}Z"
    slug = re.sub(r"[^a-z0-9]+", "-", reason.lower()).strip("-")[:60] or "recording"
    return f"{stamp}-{slug}{SUFFIX}"


class Recorder:
    """Thread-safe: subscriber callbacks call add and alarms, a timer calls save_due."""

    def __init__(self, config: RecorderConfig, clock_ns: Callable[[], int] = time.time_ns) -> None:
        self.config = config
        # The ring holds the whole window, `before` + `after` (a recording is written once its `after` is over), and
        # some slack for a save that runs late (a busy host).
        self.ring = Ring(config.before_s + config.after_s + SLACK_S, config.max_bytes)
        self.timeline = Timeline(config.before_s + config.after_s + SLACK_S)
        self.clock_ns = clock_ns
        self.pending: Optional[Pending] = None
        self._active: set[str] = set()
        self._lock = threading.Lock()
        self._kept_at: Dict[str, int] = {}   # decimated topics: when the last message kept came
        self.decimated = 0                   # messages left out by decimate_s

    def add(self, msg: RawMessage) -> bool:
        """Keep a message (False: left out, by its topic's decimation or the ring's byte bound)."""
        every = self.config.decimate_s.get(msg.topic)
        if every is not None:
            last = self._kept_at.get(msg.topic)
            if last is not None and msg.t_ns - last < every * S:
                self.decimated += 1
                return False
            self._kept_at[msg.topic] = msg.t_ns
        return self.ring.add(msg)

    def mark(self, lane: str, text: str, t_ns: Optional[int] = None) -> None:
        """A timeline lane's value from now on (timeline.LANES: alarms, process, mode)."""
        self.timeline.mark(lane, self.clock_ns() if t_ns is None else t_ns, text)

    def alarms(self, active: Iterable[Tuple[str, int, str]], t_ns: Optional[int] = None) -> Optional[Pending]:
        """The active alarms now (id, severity, text). A new one at min_severity or above starts a recording, or
        joins the one waiting for its `after` seconds. Returns the pending recording it started (None otherwise)."""
        t_ns = self.clock_ns() if t_ns is None else t_ns
        now = {(i, sev, text) for i, sev, text in active if sev >= self.config.min_severity}
        with self._lock:
            new = sorted(a for a in now if a[0] not in self._active)
            self._active = {a[0] for a in now}
            if not new:
                return None
            if self.pending is not None:
                self.pending.alarms.extend(i for i, _, _ in new)
                return None
            first = new[0]
            self.pending = Pending(f"alarm {first[0]}: {first[2]}", t_ns, [i for i, _, _ in new])
            return self.pending

    def request(self, reason: str, t_ns: Optional[int] = None) -> Pending:
        """A save asked for by hand; joins a recording already waiting."""
        t_ns = self.clock_ns() if t_ns is None else t_ns
        with self._lock:
            if self.pending is None:
                self.pending = Pending(reason, t_ns)
            return self.pending

    def save_due(self, now_ns: Optional[int] = None) -> Optional[Saved]:
        """Write the waiting recording once its `after` seconds have passed (None: nothing due)."""
        now_ns = self.clock_ns() if now_ns is None else now_ns
        with self._lock:
            p = self.pending
            if p is None or now_ns < p.end_ns(self.config.after_s):
                self.ring.expire(now_ns)
                return None
            self.pending = None
        start, end = p.at_ns - int(self.config.before_s * S), p.end_ns(self.config.after_s)
        window = self.ring.window(start, end, carry_in=True)
        os.makedirs(self.config.directory, exist_ok=True)
        name = file_name(p.at_ns, p.reason)
        path = os.path.join(self.config.directory, name)
        meta = {"reason": p.reason, "at_ns": str(p.at_ns), "before_s": str(self.config.before_s),
                "after_s": str(self.config.after_s), "alarms": ",".join(p.alarms)}
        size = write_mcap(path, window, meta)
        sidecar_error = ""
        try:
            write_sidecar(sidecar_path(path), describe(name, p.reason, p.at_ns, start, end, size, window, p.alarms,
                                                       self.timeline.window(start, end)))
        except OSError as e:  # the recording itself is safe: it is listed by name, size and time
            sidecar_error = str(e)
        deleted = retention.prune(self.config.directory, self.config.max_count, self.config.max_total_bytes)
        return Saved(name, path, size, p.reason, len(window), start, end, tuple(deleted), sidecar_error)
