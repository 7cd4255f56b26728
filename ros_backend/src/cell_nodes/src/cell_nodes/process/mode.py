"""The cell's operation mode follows the process: `running` while a run goes on (pausing included), `paused` while
paused, `idle` when it ends (done, stopped or failed). Set through the operation-mode node (source `process`).

- The mode is never taken from `alarm` (the alarms node holds it there while an error alarm is active); a run is
  refused while the mode is `alarm`, and a run going on when the mode turns `alarm` is ended (`error`).
- Only process transitions set the mode (an operator's `manual` while the process is idle stays).
- While no run is active, a `running` or `paused` mode left by the process (e.g. before a restart of the node) or
  given back by the alarms node after its alarm cleared (it restores the mode it found: the process was running) is
  set to `idle`: the process never resumes motion on a mode change by itself.
- Modes the cell file does not list are not set.
"""
from __future__ import annotations

from typing import Any, Optional, Sequence

from ..said import Said, say
from .executor import ERROR, IDLE, PAUSED, PAUSING, RUNNING

SOURCE = "process"
ALARMS_SOURCE = "alarms"
MODE_FOR_STATE = {RUNNING: "running", PAUSING: "running", PAUSED: "paused", IDLE: "idle", ERROR: "idle"}


class ModeFollower:
    def __init__(self, modes: Sequence[str], alarm_mode: str = "alarm", source: str = SOURCE) -> None:
        self.modes = list(modes)
        self.alarm_mode = alarm_mode
        self.source = source
        self.mode: Optional[str] = None       # the operation mode now (topic), None before the first message
        self.mode_source = ""
        self._target: Optional[str] = None    # the mode the last process transition asked for

    def on_mode(self, mode: str, source: str) -> None:
        self.mode, self.mode_source = mode, source

    def in_alarm(self) -> bool:
        return self.mode is not None and self.mode == self.alarm_mode

    def refusal(self) -> Optional[str]:
        return say("process.reason_alarm_mode", "the cell is in alarm: reset it first") if self.in_alarm() else None

    def transition(self, state: str) -> Optional[str]:
        """The process state changed: the mode to set now, if any (each target once per transition)."""
        target = MODE_FOR_STATE.get(state)
        if target is None or target == self._target:
            return None                       # stopping, or the same mode as the previous state (running/pausing)
        self._target = target
        return target if self.wanted(target) else None

    def wanted(self, target: str) -> bool:
        """Whether setting `target` is still right now (the worker checks again just before it calls)."""
        return target in self.modes and not self.in_alarm() and self.mode != target

    def on_set(self, target: str, ok: bool) -> None:
        if ok:  # believe our own successful set before its topic message arrives
            self.mode, self.mode_source = target, self.source

    def correction(self, active: bool) -> Optional[str]:
        """While no run is active: `idle` instead of a running/paused mode the process left or the alarms node gave
        back; else None."""
        if active or self.mode not in ("running", "paused") or "idle" not in self.modes:
            return None
        if self.mode_source in (self.source, ALARMS_SOURCE):
            return "idle"
        return None


def alarm_reason(source: str, status: Any) -> Said:
    """Why a run ended when the mode turned alarm: the alarm named as the alarms node's status (cell_msgs/SafetyStatus:
    its most severe active alarm) gives it, when it has one; its code is the alarms feature's (`alarm.<code>`)."""
    src = source or "unknown"
    if status is not None and getattr(status, "active_count", 0) and getattr(status, "alarm_id", ""):
        code = getattr(status, "code", "")
        alarm = Said(status.text, f"alarm.{code}" if code else "", [(p.key, p.value) for p in status.params])
        return say("process.reason_alarm_named", "the cell went into alarm ({source}): {alarm_id}: {alarm}; the run "
                   "was stopped", source=src, alarm_id=status.alarm_id, alarm=alarm)
    return say("process.reason_alarm", "the cell went into alarm ({source}): the run was stopped", source=src)
