"""What each source turns into conditions. Inputs are the messages' fields, read by attribute or key, so the
tests feed plain dicts and the node the ROS messages (no message class is imported here)."""
from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass
from typing import Any, Iterable, Optional, Sequence

from ..diagnostics import ERROR as D_ERROR, STALE as D_STALE, WARN as D_WARN
from .table import ERROR, INFO, WARNING, Condition


def field(obj: Any, name: str, default: Any = None) -> Any:
    """A message field or a dict key."""
    if isinstance(obj, dict):
        return obj.get(name, default)
    return getattr(obj, name, default)


# ---------------------------------------------------------------------------------------------- the robot driver
# Robot alarm ids are `robot.<group>.<kind>` (robot.arm.protective_stop, robot.left.no_state), one set per motion
# group (its /cell/manual/<group>/state); texts start with "Robot <group>: ".
# UR safety modes that are alarms: name -> (kind, severity, text). NORMAL is none.
SAFETY_ALARMS: dict[str, tuple[str, int, str]] = {
    "REDUCED": ("reduced_mode", WARNING, "reduced mode: the safety limits are lowered"),
    "RECOVERY": ("recovery", WARNING, "recovery mode: move it back inside the safety limits"),
    "PROTECTIVE_STOP": ("protective_stop", ERROR, "protective stop: the robot stopped; clear the cause, then unlock "
                                                  "it"),
    "SAFEGUARD_STOP": ("safeguard_stop", ERROR, "safeguard stop: a safeguard (door, light curtain) is open"),
    "AUTOMATIC_MODE_SAFEGUARD_STOP": ("safeguard_stop", ERROR, "safeguard stop (automatic mode): a safeguard is open"),
    "SYSTEM_THREE_POSITION_ENABLING_STOP": ("safeguard_stop", ERROR,
                                            "safeguard stop: the three-position enabling device was released"),
    "SYSTEM_EMERGENCY_STOP": ("emergency_stop", ERROR, "emergency stop from the cell (system emergency stop)"),
    "ROBOT_EMERGENCY_STOP": ("emergency_stop", ERROR, "emergency stop pressed on the robot (teach pendant)"),
    "VIOLATION": ("safety_violation", ERROR, "safety violation: the robot's safety system stopped it"),
    "FAULT": ("safety_fault", ERROR, "safety system fault: the robot's safety system stopped it"),
}
QUIET_SAFETY = ("", "NORMAL")
# UR robot modes that are alarms while the controller link is up.
ROBOT_MODE_ALARMS: dict[str, tuple[str, int, str]] = {
    "NO_CONTROLLER": ("arm_disconnected", ERROR, "the controller reports no robot arm (mode NO_CONTROLLER)"),
    "DISCONNECTED": ("arm_disconnected", ERROR, "the robot arm is not connected to its controller"),
    "CONFIRM_SAFETY": ("confirm_safety", WARNING, "the safety configuration must be confirmed on the pendant"),
    "BOOTING": ("booting", INFO, "the robot arm is booting"),
    "POWER_OFF": ("power_off", INFO, "the robot arm is powered off"),
    "BACKDRIVE": ("backdrive", WARNING, "the robot arm is in backdrive mode (brakes released by hand)"),
    "UPDATING_FIRMWARE": ("updating_firmware", WARNING, "the robot arm is updating its firmware"),
    # ros_control arms: the arm's own driver runs, but its trajectory controller does not answer.
    "CONTROLLER_NOT_RUNNING": ("controller_not_running", ERROR, "the arm's trajectory controller is not running"),
}
# The kinds of robot alarm that name the overall status (docs: SafetyStatus.status), most urgent first.
STOP_STATUS = {"emergency_stop": "emergency stop", "protective_stop": "protective stop",
               "safeguard_stop": "safeguard stop"}


def robot_alarm_id(group: str, kind: str) -> str:
    return f"robot.{group}.{kind}"


def robot_alarm_kind(alarm_id: str) -> str:
    """`robot.<group>.<kind>` -> kind ("" for any other id). Group names have no dots (they are ROS names)."""
    parts = alarm_id.split(".")
    return parts[2] if len(parts) == 3 and parts[0] == "robot" else ""


def robot_text(group: str, text: str) -> str:
    return f"Robot {group}: {text}"


def kv(**params: object) -> tuple[tuple[str, str], ...]:
    """An alarm's parameters (Alarm.msg params: diagnostic_msgs/KeyValue), in a stable order."""
    return tuple((k, str(v)) for k, v in params.items())


@dataclass(frozen=True)
class RobotInfo:
    connected: bool = False
    safety_mode: str = ""
    robot_mode: str = ""


def robot_conditions(group: str, state: Any) -> tuple[RobotInfo, list[Condition]]:
    """cell_msgs/RobotState of one motion group (the driver's /cell/manual/<group>/state) -> what it reports and
    its alarms (ids robot.<group>.<kind>)."""
    connected = bool(field(state, "connected", False))
    safety = str(field(state, "safety_mode", "") or "")
    mode = str(field(state, "robot_mode", "") or "")
    if not connected:
        host = field(state, "controller", "") or "?"
        return RobotInfo(False, "", ""), [Condition(robot_alarm_id(group, "disconnected"),
                                                    robot_text(group, f"robot controller at {host} is unreachable"),
                                                    ERROR, "robot", code="robot.disconnected",
                                                    params=kv(group=group, host=host))]
    out: list[Condition] = []
    if safety in SAFETY_ALARMS:
        kind, sev, text = SAFETY_ALARMS[safety]
        out.append(Condition(robot_alarm_id(group, kind), robot_text(group, text), sev, "robot",
                             code=f"robot.safety.{safety.lower()}", params=kv(group=group)))
    elif safety not in QUIET_SAFETY:
        out.append(Condition(robot_alarm_id(group, "safety_mode"), robot_text(group, f"unexpected safety mode "
                                                                                     f"{safety}"), WARNING, "robot",
                             code="robot.safety_mode", params=kv(group=group, mode=safety)))
    if mode in ROBOT_MODE_ALARMS:
        kind, sev, text = ROBOT_MODE_ALARMS[mode]
        out.append(Condition(robot_alarm_id(group, kind), robot_text(group, text), sev, "robot",
                             code=f"robot.mode.{mode.lower()}", params=kv(group=group)))
    fault = str(field(state, "fault", "") or "")
    if fault:  # the controller ended a move itself (an aborted trajectory): active until the next command
        out.append(Condition(robot_alarm_id(group, "motion_fault"), robot_text(group, fault), ERROR, "robot",
                             code="robot.motion_fault", params=kv(group=group, fault=fault)))
    return RobotInfo(True, safety, mode), out


def combined_robot(infos: Sequence[RobotInfo]) -> RobotInfo:
    """One RobotInfo for SafetyStatus from every group's: connected when every group's controller is; the first
    safety mode that is not NORMAL (else "" when a group's is unknown, else NORMAL); the first robot mode that is
    not RUNNING likewise. One group: its own."""
    if not infos:
        return RobotInfo()
    if len(infos) == 1:
        return infos[0]

    def pick(values: list[str], quiet: str) -> str:
        odd = next((v for v in values if v and v != quiet), None)
        if odd is not None:
            return odd
        return "" if any(not v for v in values) else quiet

    return RobotInfo(all(i.connected for i in infos), pick([i.safety_mode for i in infos], "NORMAL"),
                     pick([i.robot_mode for i in infos], "RUNNING"))


# ---------------------------------------------------------------------------------------------- device faults
def fault_conditions(alarms: Iterable[Any]) -> list[Condition]:
    """cell_msgs/AlarmList.alarms of a device (the sim's /sim/faults) -> one condition per active fault."""
    out = []
    for a in alarms:
        if not field(a, "active", False):
            continue
        since = field(a, "since", None)
        if since is not None and not isinstance(since, (int, float)):
            since = since.to_sec() if hasattr(since, "to_sec") else None
        sev = int(field(a, "severity", ERROR))
        out.append(Condition(f"device.{field(a, 'id', '?')}", str(field(a, "text", "") or field(a, "id", "?")),
                             min(max(sev, INFO), ERROR), "device", since or None))
    return out


# ---------------------------------------------------------------------------------------------- wrist force
class ForceWatch:
    """The norm of the wrist force against the limit, with hysteresis: trips above `limit`, clears below `clear`.
    The text keeps the value of the tripping reading (it does not change while the alarm stays active)."""

    def __init__(self, topic: str, limit: float, clear: float, alarm_id: str = "force.limit") -> None:
        self.topic, self.limit, self.clear, self.alarm_id = topic, limit, clear, alarm_id
        self.tripped: Optional[Condition] = None

    def update(self, force: Sequence[float]) -> list[Condition]:
        norm = math.sqrt(sum(float(f) * float(f) for f in force))
        if not math.isfinite(norm):
            return [self.tripped] if self.tripped else []
        if self.tripped is None and norm > self.limit:
            self.tripped = Condition(self.alarm_id, f"wrist force {norm:.0f} N above the {self.limit:g} N limit "
                                                    f"({self.topic})", ERROR, "force", code="force.limit",
                                     params=kv(force=f"{norm:.0f}", limit=f"{self.limit:g}", topic=self.topic))
        elif self.tripped is not None and norm < self.clear:
            self.tripped = None
        return [self.tripped] if self.tripped else []


def wrench_force(msg: Any) -> tuple[float, float, float]:
    """geometry_msgs/WrenchStamped (or a dict of the same shape) -> (fx, fy, fz)."""
    f = field(field(msg, "wrench"), "force")
    return float(field(f, "x", 0.0)), float(field(f, "y", 0.0)), float(field(f, "z", 0.0))


# ---------------------------------------------------------------------------------------------- modules
def module_conditions(modules: Iterable[Any]) -> list[Condition]:
    """cell_msgs/ModuleStates.modules -> one warning per module in state `incomplete` (some nodes down, or a launch
    or stop that did not settle). The text is the module's `message`, else its nodes that are not alive."""
    out = []
    for m in modules:
        if str(field(m, "state", "")) != "incomplete":
            continue
        name = str(field(m, "name", "?"))
        message = str(field(m, "message", "") or "")
        nodes, alive = list(field(m, "nodes", []) or []), list(field(m, "alive", []) or [])
        missing = [n for n, up in zip(nodes, alive) if not up] if len(nodes) == len(alive) else []
        why = (f": {message}" if message else f": not running: {', '.join(missing)}" if missing
               else ": some of its nodes are not running")
        code, params = (("module.incomplete_because", kv(module=name, message=message)) if message else
                        ("module.nodes_down", kv(module=name, nodes=", ".join(missing))) if missing else
                        ("module.incomplete", kv(module=name)))
        out.append(Condition(f"module.{name}", f"module {name} is incomplete{why}", WARNING, "modules",
                             code=code, params=params))
    return out


# ---------------------------------------------------------------------------------------------- silence
class SilenceWatch:
    """A source that published and then stopped for `timeout` seconds. Before its first message: nothing, unless
    the source is expected (`expected_since`: the node's start), then silent once `grace` seconds passed."""

    def __init__(self, timeout: float, expected_since: Optional[float] = None, grace: float = 0.0) -> None:
        self.timeout = timeout
        self.last: Optional[float] = None
        self.expected_since = expected_since
        self.grace = max(grace, timeout)

    def heard(self, now: float) -> None:
        self.last = now

    def silent(self, now: float) -> bool:
        if self.timeout <= 0:
            return False
        if self.last is None:
            return self.expected_since is not None and now - self.expected_since > self.grace
        return now - self.last > self.timeout


# ---------------------------------------------------------------------------------------------- diagnostics
# Alarm ids are `diagnostics.<name>` with the status name made an id (lower case, runs of other characters as "_").
def diagnostics_alarm_id(name: str) -> str:
    slug = "".join(ch if ch.isalnum() else "_" for ch in name.lower())
    return "diagnostics." + "_".join(p for p in slug.split("_") if p)


def diagnostic_conditions(statuses: Iterable[Any], rules: Sequence[Any], stale_s: float) -> list[Condition]:
    """The conditions of the current statuses (cell_nodes.diagnostics DiagStatus, STALE applied) under the cell
    file's rules (alarms.config DiagRule): the first rule whose glob matches a name decides; OK raises nothing."""
    out = []
    for s in statuses:
        rule = next((r for r in rules if fnmatch.fnmatchcase(s.name, r.match)), None)
        if rule is None:
            continue
        severity = {D_WARN: rule.warn, D_ERROR: rule.error, D_STALE: rule.stale}.get(s.level)
        if severity is None:
            continue
        if s.level == D_STALE:
            text = f"{s.name}: no report for {stale_s:g} s (stale; last: {s.message or 'no message'})"
            code, params = "diagnostics.stale", kv(name=s.name, seconds=f"{stale_s:g}", message=s.message)
        else:
            text = f"{s.name}: {s.message or ('warning' if s.level == D_WARN else 'error')}"
            # The driver's message is its own words (not ours to translate): only an empty one gets a code.
            code, params = ("", ()) if s.message else (
                "diagnostics.warning" if s.level == D_WARN else "diagnostics.error", kv(name=s.name))
        out.append(Condition(diagnostics_alarm_id(s.name), text, severity, "diagnostics", code=code, params=params))
    return out
