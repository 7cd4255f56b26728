"""Simulated device faults: what /sim/trigger_fault injects and the latched /sim/faults topic reports.

These are the devices' own state (the controller's stops, the door switch, the gripper), not the cell's alarm
list: turning faults into alarms is the alarms feature's job, which reads /sim/faults like any device state.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Mapping, Optional, Sequence

FAULTS = {
    # id: (text, severity 0 info / 1 warning / 2 error)
    "protective_stop": ("Protective stop: the robot stopped, unlock it once the cause is cleared", 2),
    "gripper_fault": ("Gripper fault: the gripper does not respond to commands", 2),
    "door_open": ("Cell door open: safeguard stop until the door is closed", 2),
    "force_limit": ("Force limit exceeded at the wrist: protective stop", 2),
}
TOOL_FAULTS = {
    "gripper": FAULTS["gripper_fault"],
    "vacuum": ("Vacuum fault: the suction does not respond to commands", 2),
}


def cell_faults(arms: Sequence[tuple[str, str]]) -> tuple[dict[str, tuple[str, int]], list[dict[str, str]]]:
    """The fault table of a cell with these arms ((group, tool kind) each), and per arm its generic fault name ->
    fault id. One arm: the ids are the names (protective_stop, gripper_fault, door_open, force_limit: the demo's).
    Several arms: "<group>.<name>" (texts start "Robot <group>: "); the door is the cell's, one door_open for all."""
    if len(arms) == 1:
        tool = arms[0][1]
        table = {"protective_stop": FAULTS["protective_stop"], f"{tool}_fault": TOOL_FAULTS[tool],
                 "door_open": FAULTS["door_open"], "force_limit": FAULTS["force_limit"]}
        return table, [{"protective_stop": "protective_stop", "tool_fault": f"{tool}_fault",
                        "door_open": "door_open", "force_limit": "force_limit"}]
    table: dict[str, tuple[str, int]] = {}
    ids = []
    for group, tool in arms:
        own = {"protective_stop": f"{group}.protective_stop", "tool_fault": f"{group}.{tool}_fault",
               "door_open": "door_open", "force_limit": f"{group}.force_limit"}
        for name, source in (("protective_stop", FAULTS["protective_stop"]), ("tool_fault", TOOL_FAULTS[tool]),
                             ("force_limit", FAULTS["force_limit"])):
            table[own[name]] = (f"Robot {group}: {source[0]}", source[1])
        ids.append(own)
    table["door_open"] = FAULTS["door_open"]
    return table, ids


@dataclass
class Fault:
    id: str
    text: str
    severity: int
    active: bool = False
    since: float = field(default_factory=time.time)  # wall time of the last change (ROS time when published)


class FaultBook:
    """Current state of every known fault; listeners hear about each change (the ROS bridge republishes)."""

    def __init__(self, table: Optional[Mapping[str, tuple[str, int]]] = None) -> None:
        self._lock = threading.Lock()
        self.faults = {k: Fault(k, text, sev) for k, (text, sev) in (table or FAULTS).items()}
        self._listeners: list[Callable[[list[Fault]], None]] = []

    def subscribe(self, fn: Callable[[list[Fault]], None]) -> None:
        self._listeners.append(fn)
        fn(self.snapshot())

    def set(self, fault_id: str, active: bool) -> None:
        with self._lock:
            fault = self.faults[fault_id]
            if fault.active == active:
                return
            fault.active = active
            fault.since = time.time()
        snap = self.snapshot()
        for fn in list(self._listeners):
            fn(snap)

    def active(self, fault_id: str) -> bool:
        return self.faults[fault_id].active

    def snapshot(self) -> list[Fault]:
        with self._lock:
            return [Fault(f.id, f.text, f.severity, f.active, f.since) for f in self.faults.values()]
