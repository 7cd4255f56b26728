"""The alarms feature's core: the sources feed one alarm table; out come the list, the overall status, what a
reset clears, and the operation-mode switches. Every input carries its timestamp (seconds); no clock, no ROS."""
from __future__ import annotations

from typing import Any, Iterable, Optional

from .config import AlarmsConfig
from .mode import ModeKeeper, ModeRequest
from .sources import (ForceWatch, RobotInfo, SilenceWatch, fault_conditions, module_conditions, robot_conditions,
                      wrench_force)
from .status import SafetyStatus, overall
from .table import ERROR, WARNING, Alarm, AlarmTable, Condition


class Alarms:
    def __init__(self, config: AlarmsConfig, now: float) -> None:
        self.config = config
        self.table = AlarmTable()
        self.robot = RobotInfo()
        self.keeper = ModeKeeper(config.alarm_mode)
        self._robot_silence = SilenceWatch(config.timeout_s, now if config.robot_expected else None,
                                           config.startup_grace_s)
        self._robot_silent = False
        # The driver's first connection after start is no "connection lost": not an alarm until the driver was
        # connected once or the start-up grace is over.
        self._start = now
        self._ever_connected = False
        self._held_back: Optional[Any] = None   # a disconnected state held back during the grace
        topics = config.wrench_topics if config.force_limit_n is not None else ()
        suffix = (lambda t: f":{t}") if len(topics) > 1 else (lambda t: "")
        self._force = {t: ForceWatch(t, config.force_limit_n or 0.0, config.force_clear or 0.0,
                                     "force.limit" + suffix(t)) for t in topics}
        self._force_silence = {t: SilenceWatch(config.timeout_s) for t in topics}
        self._force_silent: set[str] = set()
        self._force_suffix = suffix
        self._last_status: Optional[SafetyStatus] = None
        self._last_output = now
        self._list_dirty = True

    # ------------------------------------------------------------------------------------------ inputs
    def _report(self, key: str, conditions: Iterable[Condition], now: float) -> bool:
        sev = self.config.severity_for
        changed = self.table.report(key, [Condition(c.id, c.text, sev(c.id, c.severity), c.source, c.since)
                                          for c in conditions], now)
        self._list_dirty |= changed
        return changed

    def on_robot_state(self, state: Any, now: float) -> bool:
        """cell_msgs/RobotState from the robot driver."""
        self._robot_silence.heard(now)
        return self._robot_state(state, now)

    def _robot_state(self, state: Any, now: float) -> bool:
        self.robot, conditions = robot_conditions(state)
        self._ever_connected |= self.robot.connected
        self._held_back = None
        if not self._ever_connected and now - self._start <= self.config.startup_grace_s:
            self._held_back, conditions = state, []
        changed = self._report("robot", conditions, now)
        if self._robot_silent:
            self._robot_silent = False
            changed |= self._report("robot.silence", [], now)
        return changed

    def on_faults(self, topic: str, alarms: Iterable[Any], now: float) -> bool:
        """cell_msgs/AlarmList.alarms of a device fault topic (/sim/faults)."""
        return self._report(f"faults:{topic}", fault_conditions(alarms), now)

    def on_wrench(self, topic: str, msg: Any, now: float) -> bool:
        """geometry_msgs/WrenchStamped from a wrist F/T sensor."""
        watch = self._force.get(topic)
        if watch is None:
            return False
        self._force_silence[topic].heard(now)
        changed = self._report(f"force:{topic}", watch.update(wrench_force(msg)), now)
        if topic in self._force_silent:
            self._force_silent.discard(topic)
            changed |= self._report(f"force.silence:{topic}", [], now)
        return changed

    def on_modules(self, modules: Iterable[Any], now: float) -> bool:
        """cell_msgs/ModuleStates.modules (name, state) from the modules node."""
        return self._report("modules", module_conditions(modules), now)

    def tick(self, now: float) -> bool:
        """Periodic: sources that fell silent, and the active alarms' last-seen time."""
        changed = False
        if self._held_back is not None and now - self._start > self.config.startup_grace_s:
            changed |= self._robot_state(self._held_back, now)  # still never connected: now it counts
        if not self._robot_silent and self._robot_silence.silent(now):
            self._robot_silent = True
            self._held_back = None
            self.robot = RobotInfo()
            changed |= self._report("robot", [], now)  # its last modes are not known to hold any more
            heard = self._robot_silence.last is not None
            for_how_long = (f"for {self.config.timeout_s:g} s" if heard
                            else f"since the start ({self._robot_silence.grace:g} s)")
            changed |= self._report("robot.silence", [Condition(
                "robot.no_state", f"no robot state from the driver on {self.config.robot_state_topic} {for_how_long}",
                ERROR, "robot")], now)
        for topic, silence in self._force_silence.items():
            if topic not in self._force_silent and silence.silent(now):
                self._force_silent.add(topic)
                self._force[topic].tripped = None
                changed |= self._report(f"force:{topic}", [], now)
                changed |= self._report(f"force.silence:{topic}", [Condition(
                    "force.no_data" + self._force_suffix(topic),
                    f"no wrist force reading on {topic} for {self.config.timeout_s:g} s: the force limit is not "
                    f"supervised", WARNING, "force")], now)
        self.table.touch(now)
        return changed

    # ------------------------------------------------------------------------------------------ commands
    def reset(self) -> tuple[bool, str]:
        """Clear the inactive alarms; active ones stay (their cause is still there)."""
        removed, active = self.table.reset()
        self._list_dirty |= bool(removed)
        parts = [f"cleared {len(removed)} inactive alarm{'s' if len(removed) != 1 else ''} "
                 f"({', '.join(a.id for a in removed)})" if removed else "no inactive alarm to clear"]
        if active:
            parts.append(f"{len(active)} still active ({', '.join(a.id for a in active)})")
        return True, "; ".join(parts)

    # ------------------------------------------------------------------------------------------ operation mode
    def on_mode(self, mode: str, source: str) -> None:
        self.keeper.on_mode(mode, source)

    def mode_request(self) -> Optional[ModeRequest]:
        return self.keeper.decide(self.table.active_ids(ERROR))

    def mode_done(self, request: ModeRequest, ok: bool) -> None:
        self.keeper.done(request, ok)

    # ------------------------------------------------------------------------------------------ outputs
    def alarms(self) -> list[Alarm]:
        return self.table.alarms()

    def status(self) -> SafetyStatus:
        return overall(self.table.alarms(), self.robot)

    def outputs(self, now: float) -> tuple[Optional[list[Alarm]], Optional[SafetyStatus]]:
        """What to publish now: the list when it changed, the status when it changed, both once a period."""
        periodic = now - self._last_output >= self.config.publish_period_s
        if periodic:
            self._last_output = now
        alarms = status = None
        if self._list_dirty or periodic:
            alarms = self.table.alarms()
            self._list_dirty = False
        s = self.status()
        if periodic or s != self._last_status:
            status = self._last_status = s
        return alarms, status
