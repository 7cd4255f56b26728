"""The alarm table. Each source reports the complete set of conditions it detects now; an alarm is active while
any source detects it, inactive once none does (gone, but still listed), and leaves the list only on reset.

Timestamps are seconds (the node passes ROS time); nothing here reads a clock.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Iterable, Optional

INFO, WARNING, ERROR = 0, 1, 2
SEVERITY_NAMES = {INFO: "info", WARNING: "warning", ERROR: "error"}


@dataclass(frozen=True)
class Condition:
    """Something a source detects right now."""
    id: str
    text: str
    severity: int
    source: str
    since: Optional[float] = None  # when the source says it began (a device's own stamp); None: when we see it
    code: str = ""                 # what the text says, for the app's catalogue (Alarm.msg); "": the text only
    params: tuple[tuple[str, str], ...] = ()


@dataclass
class Alarm:
    id: str
    text: str
    severity: int
    source: str
    active: bool
    first_seen: float   # when it entered the list (kept while it comes and goes, until a reset removes it)
    last_seen: float    # the last time its cause was detected
    count: int = 1      # how often it became active since it entered the list
    code: str = ""
    params: tuple[tuple[str, str], ...] = ()


class AlarmTable:
    def __init__(self) -> None:
        self._alarms: dict[str, Alarm] = {}
        self._detected: dict[str, dict[str, Condition]] = {}  # source key -> what it detects now

    def report(self, source_key: str, conditions: Iterable[Condition], now: float) -> bool:
        """Replace what `source_key` detects; True when the list changed (worth publishing)."""
        self._detected[source_key] = {c.id: c for c in conditions}
        return self._update(now)

    def touch(self, now: float) -> None:
        """The sources' latest reports still hold at `now`: active alarms were seen now."""
        for a in self._alarms.values():
            if a.active:
                a.last_seen = max(a.last_seen, now)

    def _update(self, now: float) -> bool:
        merged: dict[str, Condition] = {}
        for conditions in self._detected.values():
            for c in conditions.values():
                if c.id not in merged or c.severity > merged[c.id].severity:
                    merged[c.id] = c
        changed = False
        for c in merged.values():
            a = self._alarms.get(c.id)
            if a is None:
                first = min(c.since, now) if c.since is not None and c.since > 0 else now
                self._alarms[c.id] = Alarm(c.id, c.text, c.severity, c.source, True, first, now, 1, c.code, c.params)
                changed = True
                continue
            if not a.active:
                a.active = True
                a.count += 1
                changed = True
            if (a.text, a.severity, a.source, a.code, a.params) != (c.text, c.severity, c.source, c.code, c.params):
                a.text, a.severity, a.source, a.code, a.params = c.text, c.severity, c.source, c.code, c.params
                changed = True
            a.last_seen = max(a.last_seen, now)
        for a in self._alarms.values():
            if a.active and a.id not in merged:
                a.active = False
                a.last_seen = max(a.last_seen, now)  # detected until now: the report that cleared it is newer
                changed = True
        return changed

    def reset(self) -> tuple[list[Alarm], list[Alarm]]:
        """Remove the inactive alarms. Returns (removed, still active): a reset cannot clear a cause still there."""
        removed = [a for a in self.alarms() if not a.active]
        for a in removed:
            del self._alarms[a.id]
        return removed, [a for a in self.alarms() if a.active]

    def alarms(self) -> list[Alarm]:
        """The list as shown: active first, then by severity (highest first), newest first, then by id."""
        return sorted((replace(a) for a in self._alarms.values()),
                      key=lambda a: (not a.active, -a.severity, -a.first_seen, a.id))

    def get(self, alarm_id: str) -> Optional[Alarm]:
        a = self._alarms.get(alarm_id)
        return replace(a) if a else None

    def active_ids(self, min_severity: int = INFO) -> set[str]:
        return {a.id for a in self._alarms.values() if a.active and a.severity >= min_severity}
