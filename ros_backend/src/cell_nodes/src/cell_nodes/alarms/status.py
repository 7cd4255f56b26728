"""The overall safety status of the cell, from the alarm list and the robot's last reported modes."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence

from .sources import STOP_STATUS, RobotInfo, robot_alarm_kind
from .table import ERROR, WARNING, Alarm

# Most urgent first. A robot stop names the status even if the cell file lowered that alarm's severity.
STATUSES = ("emergency stop", "protective stop", "safeguard stop", "fault", "warning", "normal")


@dataclass(frozen=True)
class SafetyStatus:
    status: str
    text: str
    active_count: int
    inactive_count: int
    highest_severity: int   # of the active alarms; -1 when none
    safety_mode: str
    robot_mode: str
    controller_connected: bool
    code: str = ""                                   # the text's code and parameters (Alarm.msg)
    params: tuple[tuple[str, str], ...] = ()
    alarm_id: str = ""


def overall(alarms: Sequence[Alarm], robot: RobotInfo) -> SafetyStatus:
    """`alarms` in list order (AlarmTable.alarms(): active first, most severe first, newest first); `robot`: every
    group's modes combined (sources.combined_robot). A stop of any group's robot names the status."""
    active = [a for a in alarms if a.active]
    highest = max((a.severity for a in active), default=-1)
    kinds = {robot_alarm_kind(a.id) for a in active}
    status = next((STOP_STATUS[k] for k in STOP_STATUS if k in kinds), None)
    if status is None:
        status = "fault" if highest >= ERROR else "warning" if highest == WARNING else "normal"
    first: Optional[Alarm] = active[0] if active else None
    text = first.text if first else "no active alarm"
    return SafetyStatus(status, text, len(active), len(alarms) - len(active), highest, robot.safety_mode,
                        robot.robot_mode, robot.connected, first.code if first else "", first.params if first else (),
                        first.id if first else "")
