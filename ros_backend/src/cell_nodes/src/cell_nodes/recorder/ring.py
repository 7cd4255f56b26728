"""A bounded ring of raw ROS 1 messages: the last `seconds` of them, at most `max_bytes` of payload."""
from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass
from dataclasses import replace
from typing import Deque, Dict, List, Optional

# What one kept message costs besides its payload (the record, the deque slot): counted so that a flood of tiny
# messages is bounded too.
OVERHEAD_BYTES = 120


@dataclass(frozen=True)
class Schema:
    """A ROS 1 message type as a subscriber's connection header gives it."""
    datatype: str        # e.g. sensor_msgs/JointState
    md5sum: str
    definition: str      # the full message definition text (gendeps --cat), dependencies included


@dataclass(frozen=True)
class RawMessage:
    topic: str
    schema: Schema
    data: bytes          # the serialized message, as on the wire
    t_ns: int            # when it was received (wall clock, ns since the epoch)
    received_ns: Optional[int] = None  # set when t_ns was moved: a value carried into a window from before it

    @property
    def cost(self) -> int:
        return len(self.data) + OVERHEAD_BYTES


@dataclass(frozen=True)
class RingStats:
    messages: int
    bytes: int
    oldest_ns: Optional[int]
    newest_ns: Optional[int]
    dropped: int         # pushed out by the bounds since the start
    refused: int         # larger than the whole byte bound: never kept


class Ring:
    """Thread-safe: subscriber callbacks add, the saver reads a window."""

    def __init__(self, seconds: float, max_bytes: int) -> None:
        if not seconds > 0 or max_bytes <= 0:
            raise ValueError(f"a ring needs seconds > 0 and max_bytes > 0, got {seconds}, {max_bytes}")
        self.span_ns = int(seconds * 1e9)
        self.max_bytes = int(max_bytes)
        self._items: Deque[RawMessage] = deque()
        # Each topic's newest message that has left the ring: a latched state published once an hour ago is still
        # the state at the start of a window (one message per topic, outside the byte bound).
        self._gone: Dict[str, RawMessage] = {}
        self._bytes = 0
        self._dropped = 0
        self._refused = 0
        self._lock = threading.Lock()

    def add(self, msg: RawMessage) -> bool:
        """Keep a message (False: it alone is over the byte bound). Older ones leave by age, then by bytes."""
        with self._lock:
            if msg.cost > self.max_bytes:
                self._refused += 1
                return False
            self._items.append(msg)
            self._bytes += msg.cost
            self._trim(msg.t_ns)
            return True

    def _trim(self, now_ns: int) -> None:
        items = self._items
        while items and (items[0].t_ns < now_ns - self.span_ns or self._bytes > self.max_bytes):
            old = items.popleft()
            self._bytes -= old.cost
            self._dropped += 1
            self._gone[old.topic] = old

    def expire(self, now_ns: int) -> None:
        """Drop what is older than the span at `now_ns` (a quiet cell still forgets)."""
        with self._lock:
            self._trim(now_ns)

    def window(self, start_ns: int, end_ns: int, carry_in: bool = False) -> List[RawMessage]:
        """The messages received in [start_ns, end_ns], oldest first (a copy: the ring goes on). With carry_in, each
        topic's last message before start_ns comes first, moved to start_ns (received_ns keeps when it came)."""
        with self._lock:
            inside = [m for m in self._items if start_ns <= m.t_ns <= end_ns]
            if not carry_in:
                return inside
            last = {t: m for t, m in self._gone.items() if m.t_ns < start_ns}
            for m in self._items:
                if m.t_ns >= start_ns:
                    break
                last[m.topic] = m
            carried = sorted(last.values(), key=lambda m: m.t_ns)
            return [replace(m, t_ns=start_ns, received_ns=m.t_ns) for m in carried] + inside

    def stats(self) -> RingStats:
        with self._lock:
            return RingStats(len(self._items), self._bytes, self._items[0].t_ns if self._items else None,
                             self._items[-1].t_ns if self._items else None, self._dropped, self._refused)
