"""The ROS log's recent history: the entries of /rosout_agg, bounded by count and by age, queried by level, node and
text the way the page filters. A log storm pushes the oldest entries out (counted), never grows the history."""
from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass
from typing import Deque, List, Optional, Tuple

LEVELS = {1: "debug", 2: "info", 4: "warn", 8: "error", 16: "fatal"}
MAX_TEXT = 4000               # characters kept of one message (a node dumping a whole file stays one entry)


@dataclass(frozen=True)
class Entry:
    t: float                  # when the node logged it (s since the epoch)
    level: int                # rosgraph_msgs/Log level: 1, 2, 4, 8, 16
    node: str
    msg: str
    file: str = ""
    function: str = ""
    line: int = 0


@dataclass(frozen=True)
class Query:
    min_level: int = 0
    node: str = ""
    text: str = ""
    max_entries: int = 0

    def matches(self, e: Entry) -> bool:
        if e.level < self.min_level or (self.node and e.node != self.node):
            return False
        if not self.text:
            return True
        needle = self.text.lower()
        return needle in e.msg.lower() or needle in e.node.lower() or needle in e.file.lower()


class LogHistory:
    """Thread-safe: the subscriber adds, the service queries."""

    def __init__(self, max_entries: int, max_age_s: float) -> None:
        if max_entries < 1 or not max_age_s > 0:
            raise ValueError(f"a log history needs max_entries >= 1 and max_age_s > 0, got {max_entries}, {max_age_s}")
        self.max_age_s = max_age_s
        self._items: Deque[Entry] = deque(maxlen=max_entries)
        self._dropped = 0
        self._lock = threading.Lock()

    def add(self, e: Entry, now: Optional[float] = None) -> None:
        if len(e.msg) > MAX_TEXT:
            e = Entry(e.t, e.level, e.node, e.msg[:MAX_TEXT] + " [cut]", e.file, e.function, e.line)
        with self._lock:
            if len(self._items) == self._items.maxlen:
                self._dropped += 1
            self._items.append(e)
            self._expire(e.t if now is None else now)

    def _expire(self, now: float) -> None:
        while self._items and self._items[0].t < now - self.max_age_s:
            self._items.popleft()
            self._dropped += 1

    def query(self, q: Query, now: float) -> Tuple[List[Entry], int, int, float]:
        """(the newest max_entries matching, oldest first; how many matched; dropped so far; seconds kept)."""
        with self._lock:
            self._expire(now)
            hits = [e for e in self._items if q.matches(e)]
            kept_s = now - self._items[0].t if self._items else 0.0
            dropped = self._dropped
        out = hits[-q.max_entries:] if q.max_entries else hits
        return out, len(hits), dropped, max(0.0, kept_s)


class InspectConfigError(ValueError):
    """An `inspect:` section the node cannot use; the message names the field."""


def parse_inspect(cell: dict) -> Tuple[int, float]:
    """The cell file's `inspect:` section: (log_keep_entries, log_keep_s)."""
    section = cell.get("inspect") or {}
    if not isinstance(section, dict):
        raise InspectConfigError(f"inspect: expected a mapping, got {section!r}")
    entries = section.get("log_keep_entries", 5000)
    seconds = section.get("log_keep_s", 600)
    if isinstance(entries, bool) or not isinstance(entries, int) or not 1 <= entries <= 1_000_000:
        raise InspectConfigError(f"inspect.log_keep_entries: expected an integer from 1 to 1000000, got {entries!r}")
    if isinstance(seconds, bool) or not isinstance(seconds, (int, float)) or not 1 <= seconds <= 86400:
        raise InspectConfigError(f"inspect.log_keep_s: expected a number from 1 to 86400, got {seconds!r}")
    return entries, float(seconds)
