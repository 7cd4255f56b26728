"""The feature's log: the last entries, newest last (published whole, latched, on every new entry)."""
from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Callable

INFO, WARNING, ERROR = "info", "warning", "error"
MAX_ENTRIES = 200


@dataclass(frozen=True)
class Entry:
    stamp: float      # Unix s
    level: str
    text: str


class LogBook:
    def __init__(self, size: int = MAX_ENTRIES, clock: Callable[[], float] = time.time) -> None:
        self._entries: deque[Entry] = deque(maxlen=size)
        self._clock = clock
        self._lock = threading.Lock()
        # The node sets this: publish the whole history. Called under the lock, so messages go out in order.
        self.on_change: Callable[[list[Entry]], None] = lambda entries: None

    def add(self, level: str, text: str) -> None:
        with self._lock:
            self._entries.append(Entry(self._clock(), level, text))
            self.on_change(list(self._entries))

    def info(self, text: str) -> None:
        self.add(INFO, text)

    def warning(self, text: str) -> None:
        self.add(WARNING, text)

    def error(self, text: str) -> None:
        self.add(ERROR, text)

    def entries(self) -> list[Entry]:
        with self._lock:
            return list(self._entries)
