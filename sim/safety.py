"""Simulated cell faults and the alarm list they raise (what /sim/trigger_fault and /cell/alarms expose)."""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Callable

FAULTS = {
    # id: (text, severity 0 info / 1 warning / 2 error)
    "protective_stop": ("Protective stop: the robot stopped, unlock it once the cause is cleared", 2),
    "gripper_fault": ("Gripper fault: the gripper does not respond to commands", 2),
    "door_open": ("Cell door open: safeguard stop until the door is closed", 2),
    "force_limit": ("Force limit exceeded at the wrist: protective stop", 2),
}


@dataclass
class Alarm:
    id: str
    text: str
    severity: int
    active: bool = False
    since: float = field(default_factory=time.time)  # wall time of the last change (ROS time when published)


class AlarmBook:
    """Current state of every known alarm; listeners hear about each change (the ROS bridge republishes)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.alarms = {k: Alarm(k, text, sev) for k, (text, sev) in FAULTS.items()}
        self._listeners: list[Callable[[list[Alarm]], None]] = []

    def subscribe(self, fn: Callable[[list[Alarm]], None]) -> None:
        self._listeners.append(fn)
        fn(self.snapshot())

    def set(self, alarm_id: str, active: bool) -> None:
        with self._lock:
            alarm = self.alarms[alarm_id]
            if alarm.active == active:
                return
            alarm.active = active
            alarm.since = time.time()
        snap = self.snapshot()
        for fn in list(self._listeners):
            fn(snap)

    def active(self, alarm_id: str) -> bool:
        return self.alarms[alarm_id].active

    def snapshot(self) -> list[Alarm]:
        with self._lock:
            return [Alarm(a.id, a.text, a.severity, a.active, a.since) for a in self.alarms.values()]
