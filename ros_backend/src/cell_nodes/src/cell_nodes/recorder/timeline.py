"""What an engineer reads first in a recording: the alarms, the process and the operation mode over time. Each
lane keeps its changes (not every message: the process state comes at 2 Hz with the same text) for as long as the
ring keeps messages, plus the value before the oldest change, so a window starts with the value it had then."""
from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass
from typing import Deque, Dict, List, Optional, Tuple

LANES: Tuple[Tuple[str, str], ...] = (("alarms", "Alarms"), ("process", "Process"), ("mode", "Operation mode"))
MAX_CHANGES = 2000          # per lane: a value flapping at 10 Hz for the whole window still fits


@dataclass(frozen=True)
class Change:
    t_ns: int
    text: str


class Timeline:
    """Thread-safe: subscriber callbacks mark, the saver reads windows."""

    def __init__(self, seconds: float, max_changes: int = MAX_CHANGES) -> None:
        self.span_ns = int(seconds * 1e9)
        self._lanes: Dict[str, Deque[Change]] = {lane: deque(maxlen=max_changes) for lane, _ in LANES}
        self._lock = threading.Lock()

    def mark(self, lane: str, t_ns: int, text: str) -> bool:
        """The lane's value from t_ns on. Returns whether it is a change (the same text again is not)."""
        with self._lock:
            changes = self._lanes[lane]
            if changes and changes[-1].text == text:
                return False
            changes.append(Change(t_ns, text))
            # Keep one change older than the span: the value a window starting then carries in.
            while len(changes) > 1 and changes[1].t_ns < t_ns - self.span_ns:
                changes.popleft()
            return True

    def window(self, start_ns: int, end_ns: int) -> Dict[str, List[Change]]:
        """Per lane: the value at start_ns (as a change at start_ns, when one was known) and the changes after it,
        up to end_ns."""
        out: Dict[str, List[Change]] = {}
        with self._lock:
            for lane, changes in self._lanes.items():
                before: Optional[Change] = None
                inside: List[Change] = []
                for c in changes:
                    if c.t_ns <= start_ns:
                        before = c
                    elif c.t_ns <= end_ns:
                        inside.append(c)
                out[lane] = ([Change(start_ns, before.text)] if before is not None else []) + inside
        return out


def alarms_text(active: List[Tuple[str, str]]) -> str:
    """The alarms lane's value: the active alarms (id, text), "" none."""
    return "; ".join(f"{i}: {text}" for i, text in sorted(active))


def process_text(state: str, step: str, message: str) -> str:
    """The process lane's value: the state with the step it is in ("running · Move to part 2 (approach)"), or why
    it failed ("error · Move to part 2 failed: ...")."""
    detail = message if state == "error" else step
    return f"{state} · {detail}" if detail else state
