"""Per-client bounded send queue with per-subscription lanes (throttle, queue_length, drop-oldest).

Why lanes: a fast topic with a small queue_length must drop its own oldest messages without touching
what another subscription or a service response of the same client has queued. Why a byte cap: a client
that stops reading must not grow server memory; past the cap it is disconnected, with a reason.
Thread-safe: ROS callback threads push, the transport's writer pops.
"""
from __future__ import annotations

import collections
import itertools
import threading
from typing import Callable, Deque, Dict, Hashable, List, Optional, Tuple

from .encoding import Frame

CONTROL = "__control__"  # lane for status, service responses, service requests: never dropped


class _Lane:
    __slots__ = ("maxlen", "throttle", "next_time", "items")

    def __init__(self, maxlen: Optional[int], throttle: float) -> None:
        self.maxlen = maxlen  # None: unbounded (control lane, byte cap still applies)
        self.throttle = throttle  # seconds between sends; 0 = as fast as the client reads
        self.next_time = 0.0
        self.items: Deque[Tuple[int, List[Frame], int]] = collections.deque()


class ClientOutbox:
    def __init__(self, max_bytes: int, default_lane_length: int, wakeup: Callable[[], None],
                 on_overflow: Callable[[str], None]) -> None:
        self._max_bytes = max_bytes
        self._default_len = max(1, default_lane_length)
        self._wakeup = wakeup
        self._on_overflow = on_overflow
        self._lock = threading.Lock()
        self._lanes: Dict[Hashable, _Lane] = {CONTROL: _Lane(None, 0.0)}
        self._seq = itertools.count()
        self._bytes = 0
        self._wake_pending = False
        self.closed = False
        self.dropped = 0  # messages dropped by drop-oldest (observable in tests and logs)
        self.sent = 0

    @property
    def queued_bytes(self) -> int:
        return self._bytes

    def configure_lane(self, key: Hashable, queue_length: int, throttle_ms: int) -> None:
        """queue_length 0 means rosbridge's 'no queueing': with a throttle only the newest message waits,
        without one a generous default bound applies (drop-oldest) so a stalled reader stays bounded."""
        throttle = max(0, throttle_ms) / 1000.0
        if queue_length > 0:
            maxlen = queue_length
        else:
            maxlen = 1 if throttle > 0 else self._default_len
        with self._lock:
            lane = self._lanes.get(key)
            if lane is None:
                self._lanes[key] = _Lane(maxlen, throttle)
            else:
                lane.maxlen, lane.throttle = maxlen, throttle
                while len(lane.items) > maxlen:
                    self._drop_oldest(lane)

    def remove_lane(self, key: Hashable) -> None:
        with self._lock:
            lane = self._lanes.pop(key, None)
            if lane is not None:
                self._bytes -= sum(n for _, _, n in lane.items)

    def _drop_oldest(self, lane: _Lane) -> None:
        _, _, n = lane.items.popleft()
        self._bytes -= n
        self.dropped += 1

    def push(self, frames: List[Frame], nbytes: int, key: Hashable = CONTROL) -> None:
        overflow: Optional[str] = None
        wake = False
        with self._lock:
            if self.closed:
                return
            lane = self._lanes.get(key)
            if lane is None:  # subscription removed while a callback was in flight
                return
            if lane.maxlen is not None and len(lane.items) >= lane.maxlen:
                self._drop_oldest(lane)
            lane.items.append((next(self._seq), frames, nbytes))
            self._bytes += nbytes
            if self._bytes > self._max_bytes:
                overflow = f"send queue exceeded {self._max_bytes} bytes (client not reading)"
                self.closed = True
                for ln in self._lanes.values():
                    ln.items.clear()
                self._bytes = 0
            elif not self._wake_pending:
                self._wake_pending = wake = True
        if overflow:
            self._on_overflow(overflow)
        elif wake:
            self._wakeup()

    def pop(self, now: float) -> Tuple[Optional[List[Frame]], Optional[float]]:
        """Next frames to write (oldest across ready lanes), or (None, seconds until a throttled lane is due)."""
        with self._lock:
            best: Optional[_Lane] = None
            delay: Optional[float] = None
            for lane in self._lanes.values():
                if not lane.items:
                    continue
                if lane.next_time > now:
                    wait = lane.next_time - now
                    delay = wait if delay is None else min(delay, wait)
                    continue
                if best is None or lane.items[0][0] < best.items[0][0]:
                    best = lane
            if best is None:
                self._wake_pending = False
                return None, delay
            _, frames, n = best.items.popleft()
            self._bytes -= n
            self.sent += 1
            if best.throttle:
                best.next_time = now + best.throttle
            return frames, None

    def close(self) -> None:
        with self._lock:
            self.closed = True
            self._lanes.clear()
            self._bytes = 0
