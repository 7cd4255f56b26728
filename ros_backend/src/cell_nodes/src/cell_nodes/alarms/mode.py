"""When the alarms node switches the cell's operation mode to `alarm`, and when it switches it back.

- An error alarm (severity error or higher) that becomes active switches the mode to `alarm` (source `alarms`),
  remembering the mode it had. Each new error alarm does this once: if someone then sets another mode while the
  error is still active (an operator recovering the cell), the node does not fight them.
- When no error alarm is active any more, the mode goes back to the remembered one, but only if it is still
  `alarm` set by this node; a mode somebody else set in between is left alone.
- A failed switch (service down, refused) is retried on the next decision while it is still wanted.
Nothing is decided before the mode is known (the latched mode topic).

What the keeper remembers (the mode to give back, the error alarms already acted on, a switch still due) is its
`memory()`: the node saves it in a state file and `restore`s it after its own restart, so a restart neither loses
the mode to give back nor switches again for an error the operator is already recovering from. Until the sources
have reported again after such a restart, `decide(..., settled=False)` gives nothing back and forgets no alarm it
acted on: an alarm missing from the table then may only not be known yet.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Optional, Sequence

SOURCE = "alarms"


@dataclass(frozen=True)
class ModeRequest:
    mode: str
    reason: str


class ModeKeeper:
    def __init__(self, alarm_mode: str = "alarm", source: str = SOURCE) -> None:
        self.alarm_mode = alarm_mode
        self.source = source
        self.mode: Optional[str] = None       # the current operation mode, from the topic
        self.mode_source = ""
        self.previous: Optional[str] = None   # the mode before this node set `alarm`
        self._seen: set[str] = set()          # error alarms already acted on
        self._want_alarm = False              # a switch to alarm is due (not yet seen on the topic)

    def on_mode(self, mode: str, source: str) -> None:
        self.mode, self.mode_source = mode, source
        if mode == self.alarm_mode:
            self._want_alarm = False
        if self.previous is not None and not self.ours():
            self.previous = None              # someone else took over the mode: nothing to give back

    def ours(self) -> bool:
        return self.mode == self.alarm_mode and self.mode_source == self.source

    def decide(self, active_errors: set[str], settled: bool = True) -> Optional[ModeRequest]:
        """The switch to ask the operation-mode node for now, if any. `settled` False: after a restart, before every
        source reported again (a new error still switches to alarm at once; nothing is given back yet)."""
        if self.mode is None or not self.alarm_mode:
            return None
        new = active_errors - self._seen
        self._seen = set(active_errors) if settled else self._seen | active_errors
        if active_errors:
            if new and self.mode != self.alarm_mode:
                self._want_alarm = True
                if self.previous is None:
                    self.previous = self.mode
            if self._want_alarm and self.mode != self.alarm_mode:
                return ModeRequest(self.alarm_mode, "error alarm active: " + ", ".join(sorted(active_errors)))
            return None
        if not settled:
            return None                       # no error known yet: it may only not have been reported again
        self._want_alarm = False
        if self.ours() and self.previous is not None:
            return ModeRequest(self.previous, "no error alarm active any more")
        if not self.ours():
            self.previous = None
        return None

    def done(self, request: ModeRequest, ok: bool) -> None:
        """The operation-mode node's answer; the topic then confirms the change (on_mode)."""
        if not ok:
            return                            # still wanted: asked again on the next decision
        if request.mode == self.alarm_mode:
            self._want_alarm = False          # not asked again while the topic catches up
        else:
            self.previous = None

    # ------------------------------------------------------------------------------------------ across a restart
    def memory(self) -> dict[str, Any]:
        """What must survive a restart of the node (JSON-ready)."""
        return {"alarm_mode": self.alarm_mode, "previous": self.previous, "seen": sorted(self._seen),
                "want_alarm": self._want_alarm}

    def restore(self, memory: Mapping[str, Any]) -> None:
        """Take back a memory that passed memory_problem. The mode itself comes from the topic, as at any start."""
        self.previous = memory["previous"]
        self._seen = set(memory["seen"])
        self._want_alarm = bool(memory["want_alarm"])

    @staticmethod
    def remembers(memory: Mapping[str, Any]) -> bool:
        """Whether a memory holds anything (an empty one needs no care after the restart)."""
        return bool(memory.get("previous") or memory.get("seen") or memory.get("want_alarm"))


def memory_problem(memory: Mapping[str, Any], alarm_mode: str, modes: Sequence[str]) -> Optional[str]:
    """What is wrong with a saved memory for this cell (malformed, or stale: made for other modes), or None."""
    previous, seen, want = memory.get("previous"), memory.get("seen"), memory.get("want_alarm")
    if memory.get("alarm_mode") != alarm_mode:
        return (f"saved for alarm mode {memory.get('alarm_mode')!r}, the cell file's is {alarm_mode!r} "
                "(stale: the cell file changed)")
    if previous is not None and not isinstance(previous, str):
        return f"previous: expected a mode name or null, got {previous!r}"
    if previous is not None and (previous not in modes or previous == alarm_mode):
        return (f"previous: {previous!r} is not a mode to give back (the cell file's modes: {', '.join(modes)}; "
                "stale: the cell file changed)")
    if not isinstance(seen, list) or not all(isinstance(x, str) and x for x in seen):
        return f"seen: expected a list of alarm ids, got {seen!r}"
    if not isinstance(want, bool):
        return f"want_alarm: expected true or false, got {want!r}"
    return None
