"""diagnostic_msgs as the cell's nodes use them, without ROS: one component's status, what a driver reports, and
the statuses heard on /diagnostics with the silent ones marked STALE (what diagnostic_aggregator does), for the
Inspect page's tree and the alarms node's rules. Fields are read by attribute or key, so tests feed dicts."""
from __future__ import annotations

import threading
from dataclasses import dataclass, replace
from typing import Any, Iterable, Optional

OK, WARN, ERROR, STALE = 0, 1, 2, 3
LEVEL_NAMES = {OK: "ok", WARN: "warn", ERROR: "error", STALE: "stale"}
STALE_S = 5.0     # diagnostic_aggregator's default: a status not reported again within 5 s is stale


@dataclass(frozen=True)
class DiagStatus:
    name: str
    level: int
    message: str
    hardware_id: str = ""
    values: tuple[tuple[str, str], ...] = ()
    node: str = ""          # who published it (the connection header's callerid)
    received: float = 0.0   # when it came (s)


def _get(obj: Any, name: str, default: Any = None) -> Any:
    return obj.get(name, default) if isinstance(obj, dict) else getattr(obj, name, default)


def _level(raw: Any) -> int:
    """A level as rospy gives it (an int, or a 1-byte bytes for `byte` in some generators)."""
    if isinstance(raw, (bytes, bytearray)):
        raw = raw[0] if raw else 0
    level = int(raw or 0)
    return level if level in LEVEL_NAMES else ERROR   # an unknown level is not "fine"


def statuses_of(array: Any, node: str, now: float) -> list[DiagStatus]:
    """The statuses of one diagnostic_msgs/DiagnosticArray."""
    out = []
    for s in _get(array, "status", None) or []:
        values = tuple((str(_get(kv, "key", "")), str(_get(kv, "value", ""))) for kv in _get(s, "values", None) or [])
        out.append(DiagStatus(str(_get(s, "name", "")), _level(_get(s, "level", 0)), str(_get(s, "message", "")),
                              str(_get(s, "hardware_id", "")), values, node, now))
    return out


class DiagnosticsTracker:
    """The latest status of each name; thread-safe (the subscriber adds, a timer or a service reads)."""

    def __init__(self, stale_s: float = STALE_S, max_names: int = 1000) -> None:
        self.stale_s = stale_s
        self.max_names = max_names    # a publisher inventing names cannot grow it without bound
        self._by_name: dict[str, DiagStatus] = {}
        self._lock = threading.Lock()

    def add(self, statuses: Iterable[DiagStatus]) -> None:
        with self._lock:
            for s in statuses:
                if s.name not in self._by_name and len(self._by_name) >= self.max_names:
                    oldest = min(self._by_name.values(), key=lambda x: x.received)
                    del self._by_name[oldest.name]
                self._by_name[s.name] = s

    def current(self, now: float) -> list[DiagStatus]:
        """Every status heard, by name; one not reported again within stale_s has level STALE (message kept)."""
        with self._lock:
            items = sorted(self._by_name.values(), key=lambda s: s.name)
        return [replace(s, level=STALE) if now - s.received > self.stale_s else s for s in items]

    def forget_nodes(self, nodes: Iterable[str]) -> list[str]:
        """Drop the statuses these nodes published (a module stopped on purpose); returns their names."""
        gone = set(nodes)
        with self._lock:
            names = sorted(n for n, s in self._by_name.items() if s.node in gone)
            for n in names:
                del self._by_name[n]
        return names


def level_name(level: int) -> str:
    return LEVEL_NAMES.get(level, "error")


def status(name: str, level: int, message: str, values: Optional[Iterable[tuple[str, Any]]] = None,
           hardware_id: str = "") -> DiagStatus:
    """What a node reports about one of its components (values formatted as text)."""
    return DiagStatus(name, level, message, hardware_id, tuple((k, _text(v)) for k, v in values or ()))


def _text(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)
