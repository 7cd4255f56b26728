"""The alarms feature's core: the sources feed one alarm table; out come the list, the overall status, what a
reset clears, and the operation-mode switches. Every input carries its timestamp (seconds); no clock, no ROS."""
from __future__ import annotations

from dataclasses import replace
from typing import Any, Iterable, Mapping, Optional

from ..diagnostics import DiagnosticsTracker, statuses_of
from .config import AlarmsConfig, default_robot_state_topic
from .mode import ModeKeeper, ModeRequest, memory_problem
from .sources import (ForceWatch, RobotInfo, SilenceWatch, combined_robot, diagnostic_conditions, fault_conditions,
                      field, kv, module_conditions, robot_alarm_id, robot_conditions, robot_text, wrench_force)
from .status import SafetyStatus, overall
from .table import ERROR, WARNING, Alarm, AlarmTable, Condition


class _RobotWatch:
    """One motion group's robot state source: its last modes, silence, and the start-up grace."""

    def __init__(self, group: str, topic: str, config: AlarmsConfig, now: float, expected: bool) -> None:
        self.group, self.topic = group, topic
        self.info = RobotInfo()
        self.silence = SilenceWatch(config.timeout_s, now if expected else None, config.startup_grace_s)
        self.silent = False
        # The driver's first connection after start is no "connection lost": not an alarm until the driver was
        # connected once or the start-up grace is over.
        self.ever_connected = False
        self.held_back: Optional[Any] = None    # a disconnected state held back during the grace


class Alarms:
    def __init__(self, config: AlarmsConfig, now: float) -> None:
        self.config = config
        self.table = AlarmTable()
        self.keeper = ModeKeeper(config.alarm_mode)
        self._start = now
        # Every motion group of the cell, each watched on its own state topic (robot.<group>.* alarms).
        self._robots: dict[str, _RobotWatch] = {
            g: _RobotWatch(g, topic, config, now, config.robot_expected) for g, topic in config.robot_state_topics}
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
        # After a restart with a remembered mode: the sources not heard since the start. Until each has reported (or
        # the start-up grace is over, when the silent ones are alarms), the remembered mode is not given back.
        self._holding = False
        self._unheard: set[str] = set()
        self._diagnostics = DiagnosticsTracker(config.diagnostics_stale_s)
        self._stopped_nodes: set[str] = set()   # the nodes of modules that are inactive (stopped on purpose)

    # ------------------------------------------------------------------------------------------ inputs
    def _report(self, key: str, conditions: Iterable[Condition], now: float) -> bool:
        sev = self.config.severity_for
        changed = self.table.report(key, [replace(c, severity=sev(c.id, c.severity)) for c in conditions], now)
        self._list_dirty |= changed
        return changed

    @property
    def robot(self) -> RobotInfo:
        """Every group's last reported modes, combined for SafetyStatus."""
        return combined_robot([w.info for w in self._robots.values()])

    def _watch(self, group: str) -> _RobotWatch:
        w = self._robots.get(group)
        if w is None:  # a group the cell file does not list: watched from its first message on
            w = self._robots[group] = _RobotWatch(group, default_robot_state_topic(group), self.config, self._start,
                                                  False)
        return w

    def on_robot_state(self, group: str, state: Any, now: float) -> bool:
        """cell_msgs/RobotState of a motion group from the robot driver (/cell/manual/<group>/state)."""
        w = self._watch(group)
        w.silence.heard(now)
        return self._robot_state(w, state, now)

    def _robot_state(self, w: _RobotWatch, state: Any, now: float) -> bool:
        w.info, conditions = robot_conditions(w.group, state)
        w.ever_connected |= w.info.connected
        w.held_back = None
        if not w.ever_connected and now - self._start <= self.config.startup_grace_s:
            w.held_back, conditions = state, []
        changed = self._report(f"robot:{w.group}", conditions, now)
        if w.silent:
            w.silent = False
            changed |= self._report(f"robot.silence:{w.group}", [], now)
        return changed

    def on_faults(self, topic: str, alarms: Iterable[Any], now: float) -> bool:
        """cell_msgs/AlarmList.alarms of a device fault topic (/sim/faults)."""
        self._unheard.discard(f"faults:{topic}")
        return self._report(f"faults:{topic}", fault_conditions(alarms), now)

    def on_wrench(self, topic: str, msg: Any, now: float) -> bool:
        """geometry_msgs/WrenchStamped from a wrist F/T sensor."""
        watch = self._force.get(topic)
        if watch is None:
            return False
        self._force_silence[topic].heard(now)
        self._unheard.discard(f"force:{topic}")
        changed = self._report(f"force:{topic}", watch.update(wrench_force(msg)), now)
        if topic in self._force_silent:
            self._force_silent.discard(topic)
            changed |= self._report(f"force.silence:{topic}", [], now)
        return changed

    def on_modules(self, modules: Iterable[Any], now: float) -> bool:
        """cell_msgs/ModuleStates.modules (name, state, nodes) from the modules node."""
        modules = list(modules)
        self._unheard.discard("modules")
        changed = self._report("modules", module_conditions(modules), now)
        # A module stopped on purpose (inactive) leaves no stale diagnostics behind: its nodes' statuses go.
        self._stopped_nodes = {n for m in modules if field(m, "state") == "inactive" for n in field(m, "nodes") or []}
        if self._stopped_nodes and self._diagnostics.forget_nodes(self._stopped_nodes):
            changed |= self._diagnostics_report(now)
        return changed

    def on_diagnostics(self, array: Any, node: str, now: float) -> bool:
        """diagnostic_msgs/DiagnosticArray from `node` (the publisher's name, from the connection header)."""
        if node in self._stopped_nodes:
            return False  # a last report while its module is being stopped
        self._diagnostics.add(statuses_of(array, node, now))
        return self._diagnostics_report(now)

    def _diagnostics_report(self, now: float) -> bool:
        if not self.config.diagnostics_rules:
            return False
        return self._report("diagnostics", diagnostic_conditions(
            self._diagnostics.current(now), self.config.diagnostics_rules, self.config.diagnostics_stale_s), now)

    def tick(self, now: float) -> bool:
        """Periodic: sources that fell silent, and the active alarms' last-seen time."""
        changed = False
        for w in self._robots.values():
            changed |= self._robot_tick(w, now)
        for topic, silence in self._force_silence.items():
            if topic not in self._force_silent and silence.silent(now):
                self._force_silent.add(topic)
                self._force[topic].tripped = None
                changed |= self._report(f"force:{topic}", [], now)
                changed |= self._report(f"force.silence:{topic}", [Condition(
                    "force.no_data" + self._force_suffix(topic),
                    f"no wrist force reading on {topic} for {self.config.timeout_s:g} s: the force limit is not "
                    f"supervised", WARNING, "force", code="force.no_data",
                    params=kv(topic=topic, seconds=f"{self.config.timeout_s:g}"))], now)
        changed |= self._diagnostics_report(now)   # statuses that fell silent become stale
        self.table.touch(now)
        return changed

    def _robot_tick(self, w: _RobotWatch, now: float) -> bool:
        changed = False
        if w.held_back is not None and now - self._start > self.config.startup_grace_s:
            changed |= self._robot_state(w, w.held_back, now)  # still never connected: now it counts
        if not w.silent and w.silence.silent(now):
            w.silent = True
            w.held_back = None
            w.info = RobotInfo()
            changed |= self._report(f"robot:{w.group}", [], now)  # its last modes are not known to hold any more
            heard = w.silence.last is not None
            for_how_long = (f"for {self.config.timeout_s:g} s" if heard
                            else f"since the start ({w.silence.grace:g} s)")
            seconds = self.config.timeout_s if heard else w.silence.grace
            changed |= self._report(f"robot.silence:{w.group}", [Condition(
                robot_alarm_id(w.group, "no_state"),
                robot_text(w.group, f"no robot state from the driver on {w.topic} {for_how_long}"), ERROR,
                "robot", code="robot.no_state" if heard else "robot.no_state_since_start",
                params=kv(group=w.group, topic=w.topic, seconds=f"{seconds:g}"))], now)
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

    def mode_request(self, now: Optional[float] = None) -> Optional[ModeRequest]:
        return self.keeper.decide(self.table.active_ids(ERROR), self.settled(now))

    # ------------------------------------------------------------------------------------------ across a restart
    def memory(self) -> dict[str, Any]:
        """What the node saves in its state file (the mode keeper's memory)."""
        return self.keeper.memory()

    def restore(self, memory: Mapping[str, Any]) -> Optional[str]:
        """Take back the memory saved before a restart; returns what is wrong with it (then nothing is taken)."""
        why = memory_problem(memory, self.config.alarm_mode, self.config.modes)
        if why is not None:
            return why
        self.keeper.restore(memory)
        if ModeKeeper.remembers(memory):
            self._holding = True
            self._unheard = {f"faults:{t}" for t in self.config.fault_topics} | {f"force:{t}" for t in self._force}
            self._unheard.add("modules")
        return None

    def settled(self, now: Optional[float] = None) -> bool:
        """Whether the alarm table is known again after a restart with a remembered mode: every source reported
        (a robot's state counts once it is not held back as a first connection), or the start-up grace is over
        (the silent sources are alarms by then: tick raises them at the same `now`). Always true without a
        remembered mode. Once true, it stays true."""
        if not self._holding:
            return True
        over = now is not None and now - self._start > max(self.config.startup_grace_s, self.config.timeout_s)
        robots = all(w.silence.last is not None and w.held_back is None for w in self._robots.values())
        if over or (robots and not self._unheard):
            self._holding = False
        return not self._holding

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
