"""Topics watched on demand for the Inspect page: the measured rate and bandwidth (rostopic hz / bw) and the last
message (rostopic echo -n 1) of the topics someone is looking at. A topic is watched from the first request until
IDLE_S after the last one, so the robot PC subscribes only while a page shows it; at most MAX_WATCHES at once.
Pure: the rospy layer passes in how to subscribe and what arrives (serialized size, raw bytes, arrival time)."""
from __future__ import annotations

import math
import re
import threading
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable, Deque, Optional

WINDOW_S = 10.0          # the figures are over the last 10 s (rostopic hz's default window is about this)
MAX_SAMPLES = 20_000     # 2 kHz over the window; a faster topic's figures are over a shorter span
IDLE_S = 10.0            # a watch ends this long after its last request
MAX_WATCHES = 8          # topics watched at once (each is a subscription of the robot PC's)
MAX_ITEMS = 16           # array items an echo keeps
MAX_STRING = 1000        # characters an echo keeps of one string


class WatchRefused(ValueError):
    """A request the watches cannot serve (the message says why)."""


@dataclass(frozen=True)
class Stats:
    messages: int
    window_s: float
    rate_hz: float
    bandwidth_bps: float
    mean_bytes: float
    last_age_s: float    # -1: nothing yet


class TopicWatch:
    """One topic's arrivals over the last WINDOW_S and its last message (raw). Thread-safe."""

    def __init__(self, topic: str, started: float, unsubscribe: Callable[[], None]) -> None:
        self.topic = topic
        self.started = started
        self.last_request = started
        self.type = ""
        self.unsubscribe = unsubscribe
        self._samples: Deque[tuple[float, int]] = deque(maxlen=MAX_SAMPLES)
        self._last: Optional[tuple[float, bytes]] = None
        self._lock = threading.Lock()

    def add(self, t: float, raw: bytes, msg_type: str = "") -> None:
        with self._lock:
            self._samples.append((t, len(raw)))
            self._last = (t, raw)
            if msg_type:
                self.type = msg_type

    def stats(self, now: float) -> Stats:
        with self._lock:
            while self._samples and self._samples[0][0] < now - WINDOW_S:
                self._samples.popleft()
            samples = list(self._samples)
            last = self._last
        window = max(0.0, min(WINDOW_S, now - self.started))
        n = len(samples)
        span = samples[-1][0] - samples[0][0] if n >= 2 else 0.0
        total = sum(s for _t, s in samples)
        # bytes over the time since the oldest sample kept (rostopic bw), or over the window while it fills
        bw_span = now - samples[0][0] if n else 0.0
        return Stats(messages=n, window_s=window, rate_hz=(n - 1) / span if span > 0 else 0.0,
                     bandwidth_bps=total / bw_span if bw_span > 0 else 0.0, mean_bytes=total / n if n else 0.0,
                     last_age_s=max(0.0, now - last[0]) if last else -1.0)

    def last(self) -> Optional[tuple[float, bytes]]:
        with self._lock:
            return self._last


class Watches:
    """The watched topics. subscribe(topic, watch) starts delivering to watch.add and returns how to stop."""

    def __init__(self, subscribe: Callable[[str, TopicWatch], Callable[[], None]], idle_s: float = IDLE_S,
                 max_watches: int = MAX_WATCHES) -> None:
        self._subscribe = subscribe
        self.idle_s = idle_s
        self.max_watches = max_watches
        self._watches: dict[str, TopicWatch] = {}
        self._lock = threading.Lock()

    def touch(self, topic: str, now: float) -> TopicWatch:
        """The topic's watch, started if need be; it lives idle_s from now."""
        self.expire(now)
        with self._lock:
            w = self._watches.get(topic)
            if w is None:
                if len(self._watches) >= self.max_watches:
                    raise WatchRefused(f"already measuring {len(self._watches)} topics (at most {self.max_watches} "
                                       f"at once); try again when a page stops showing one")
                w = TopicWatch(topic, now, lambda: None)
                w.unsubscribe = self._subscribe(topic, w)
                self._watches[topic] = w
            w.last_request = now
            return w

    def expire(self, now: float) -> list[str]:
        """Stop the watches nobody asked for within idle_s; returns their topics."""
        with self._lock:
            gone = [w for w in self._watches.values() if now - w.last_request > self.idle_s]
            for w in gone:
                del self._watches[w.topic]
        for w in gone:
            w.unsubscribe()
        return [w.topic for w in gone]

    def topics(self) -> list[str]:
        with self._lock:
            return sorted(self._watches)

    def close(self) -> None:
        with self._lock:
            gone, self._watches = list(self._watches.values()), {}
        for w in gone:
            w.unsubscribe()


def to_tree(value: Any, slot_type: str = "") -> Any:
    """A message as JSON-ready data for a readable tree: fields in order, long arrays and strings cut, byte arrays
    as their length, times as secs/nsecs, NaN and infinities as text."""
    if isinstance(value, (bytes, bytearray)) or (slot_type.startswith(("uint8[", "char[")) and isinstance(value, (list, tuple))):
        return f"<{len(value)} bytes>"
    slots = getattr(value, "__slots__", None)
    types = getattr(value, "_slot_types", None)
    if slots is not None and types is not None:
        return {s: to_tree(getattr(value, s), t) for s, t in zip(slots, types)}
    if hasattr(value, "secs") and hasattr(value, "nsecs"):
        return {"secs": int(value.secs), "nsecs": int(value.nsecs)}
    if isinstance(value, (list, tuple)):
        item_type = slot_type.split("[", 1)[0]
        out = [to_tree(v, item_type) for v in value[:MAX_ITEMS]]
        if len(value) > MAX_ITEMS:
            out.append(f"... {len(value) - MAX_ITEMS} more ({len(value)} items)")
        return out
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, str) and len(value) > MAX_STRING:
        return value[:MAX_STRING] + f"... ({len(value)} characters)"
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


def topic_name_problem(topic: str) -> Optional[str]:
    """Why `topic` is not a global ROS topic name, or None."""
    if not re.fullmatch(r"(/[A-Za-z][A-Za-z0-9_]*)+", topic or ""):
        return f"{topic!r} is not a global topic name (like /joint_states)"
    return None
