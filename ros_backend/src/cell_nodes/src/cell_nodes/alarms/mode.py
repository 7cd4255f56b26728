"""When the alarms node switches the cell's operation mode to `alarm`, and when it switches it back.

- An error alarm (severity error or higher) that becomes active switches the mode to `alarm` (source `alarms`),
  remembering the mode it had. Each new error alarm does this once: if someone then sets another mode while the
  error is still active (an operator recovering the cell), the node does not fight them.
- When no error alarm is active any more, the mode goes back to the remembered one, but only if it is still
  `alarm` set by this node; a mode somebody else set in between is left alone.
- A failed switch (service down, refused) is retried on the next decision while it is still wanted.
Nothing is decided before the mode is known (the latched mode topic).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

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

    def decide(self, active_errors: set[str]) -> Optional[ModeRequest]:
        """The switch to ask the operation-mode node for now, if any."""
        if self.mode is None or not self.alarm_mode:
            return None
        new = active_errors - self._seen
        self._seen = set(active_errors)
        if active_errors:
            if new and self.mode != self.alarm_mode:
                self._want_alarm = True
                if self.previous is None:
                    self.previous = self.mode
            if self._want_alarm and self.mode != self.alarm_mode:
                return ModeRequest(self.alarm_mode, "error alarm active: " + ", ".join(sorted(active_errors)))
            return None
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
