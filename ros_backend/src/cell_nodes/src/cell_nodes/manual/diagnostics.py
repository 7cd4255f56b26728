"""The robot driver's diagnostics (/diagnostics), as a real driver reports them: per motion group, the controller
link and modes, and the rate the arm's joint states come at. Pure: the node passes the state and the rate."""
from __future__ import annotations

import threading
from collections import deque
from typing import Deque

from ..diagnostics import ERROR, OK, WARN, DiagStatus, status
from .driver import DriverState


class RateMeter:
    """Samples per second over the last window_s (the joint states the driver publishes). Thread-safe: the poll
    thread ticks, a timer reads."""

    def __init__(self, window_s: float = 2.0) -> None:
        self.window_s = window_s
        self._times: Deque[float] = deque()
        self._lock = threading.Lock()

    def tick(self, now: float) -> None:
        with self._lock:
            self._times.append(now)
            self._drop(now)

    def rate(self, now: float) -> float:
        with self._lock:
            self._drop(now)
            return len(self._times) / self.window_s

    def _drop(self, now: float) -> None:
        while self._times and self._times[0] < now - self.window_s:
            self._times.popleft()


def driver_diagnostic(node: str, group: str, state: DriverState, joint_rate_hz: float, expected_hz: float) -> DiagStatus:
    """ERROR without the controller; WARN when the joint states come at less than half the expected rate or the
    robot is not in normal operation (safety mode not NORMAL); else OK."""
    values = [("controller", state.controller or "-"), ("robot mode", state.robot_mode or "-"),
              ("safety mode", state.safety_mode or "-"), ("joint states (Hz)", f"{joint_rate_hz:.1f}"),
              ("expected (Hz)", f"{expected_hz:g}"), ("motion", state.motion or "-")]
    if not state.connected:
        level, message = ERROR, state.message or "controller not connected"
    elif joint_rate_hz < expected_hz / 2:
        level, message = WARN, f"joint states at {joint_rate_hz:.0f} Hz (expected {expected_hz:g})"
    elif state.safety_mode not in ("", "NORMAL"):
        level, message = WARN, f"safety mode {state.safety_mode}"
    else:
        level, message = OK, "connected"
    return status(f"{node.lstrip('/')}: {group} controller", level, message, values)
