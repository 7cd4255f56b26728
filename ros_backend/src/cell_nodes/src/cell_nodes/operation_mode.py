"""The cell's operation mode: the allowed modes come from the cell file; no ROS here."""
from __future__ import annotations

from dataclasses import dataclass, field
import time
from typing import Sequence


@dataclass
class ModeState:
    mode: str
    source: str
    stamp: float = field(default_factory=time.time)


class OperationMode:
    def __init__(self, modes: list[str], initial: str | None = None) -> None:
        if not modes:
            raise ValueError("the cell file lists no operation modes")
        self.modes = list(modes)
        start = initial or self.modes[0]
        if start not in self.modes:
            raise ValueError(f"initial mode {start!r} is not one of {self.modes}")
        self.state = ModeState(start, "startup")

    def set(self, mode: str, source: str, unless: Sequence[str] = ()) -> tuple[bool, str]:
        """Change the mode; refuse modes the cell file does not list, and any change while the mode is one of
        `unless` (a compare-and-set: the caller's view of the mode may be out of date by the time it asks)."""
        if mode not in self.modes:
            return False, f"unknown mode {mode!r}; the cell's modes are: {', '.join(self.modes)}"
        if self.state.mode in unless:
            return False, f"the mode is {self.state.mode} (set by {self.state.source}): not changed to {mode}"
        self.state = ModeState(mode, source or "unknown")
        return True, f"mode is now {mode}"
