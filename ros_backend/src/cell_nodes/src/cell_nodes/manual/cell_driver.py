"""The cell's robot driver: one ManualDriver per arm (per distinct controller host), and the routing of the node's
services and topics to them. No ROS here: the node (scripts/manual_node) calls these methods and publishes what
the callbacks report; the tests use fake drivers.

- a request that names a group (moves, their preview, get_pose, jogs) goes to the driver of that group's arm; a tool
  action to the driver of the tool's group; a name no arm has is refused with the cell's names, as a single driver
  refuses it;
- stop asks every arm at once (in parallel) and answers after all of them answered;
- a jog goes to its group's arm (each driver keeps its own dead-man timeout); a jog naming no group of the cell is
  refused on every arm (a running jog stops: never carry on after a bad command);
- the state is per group: the arm's state with `motion_group` set to the group.
"""
from __future__ import annotations

import threading
from dataclasses import replace
from typing import Callable, Mapping, Optional, Protocol, Sequence

from .config import Arm, Group, ManualConfig, plan_arms
from ..said import Said, say
from .driver import DriverState, Snapshot, unknown_group, unknown_tool
from .limits import Limits


class ArmDriver(Protocol):
    """What the cell driver uses of a ManualDriver (the tests pass fakes)."""

    host: str
    on_change: Callable[[], None]
    on_sample: Callable[[Snapshot], None]

    def start(self) -> None: ...
    def shutdown(self) -> None: ...
    def state(self) -> DriverState: ...
    def snapshot(self) -> Snapshot: ...
    @property
    def connected(self) -> bool: ...
    def get_pose(self, group: str) -> tuple[bool, str, list[float], list[float]]: ...
    def move_named(self, group: str, name: str, speed: float = 0.0, acceleration: float = 0.0) -> tuple[bool, str]: ...
    def move_relative(self, group: str, offset: Sequence[float], frame: str, speed: float = 0.0,
                      acceleration: float = 0.0) -> tuple[bool, str]: ...
    def move_pose(self, group: str, pose: Sequence[float], speed: float = 0.0,
                  acceleration: float = 0.0) -> tuple[bool, str]: ...
    def preview_move(self, group: str, kind: str, name: str = "", offset: Sequence[float] = (), frame: str = "",
                     pose: Sequence[float] = ()) -> tuple[bool, str, list[str], list[float], list[float]]: ...
    def tool_action(self, tool: str, action: str) -> tuple[bool, str]: ...
    def stop(self, wait: bool = True) -> tuple[bool, str]: ...
    def jog(self, group: str, mode: str, axis: int, direction: int, speed: float, frame: str = "base",
            age_s: Optional[float] = None, press: int = 0) -> None: ...
    def refuse_jog(self, why: str) -> None: ...


class CellDriver:
    def __init__(self, config: ManualConfig, arms: Sequence[Arm], drivers: Sequence[ArmDriver],
                 limits: Limits) -> None:
        if len(arms) != len(drivers):
            raise ValueError("one driver per arm")
        self.config = config
        self.arms = tuple(arms)
        self.drivers = tuple(drivers)
        self.limits = limits
        self._group_arm = {g: i for i, arm in enumerate(self.arms) for g in arm.groups}
        self._tool_arm = {t: i for i, arm in enumerate(self.arms) for t in arm.tools}
        # The node sets these: on_change(arm) -> publish the states of the arm's groups now;
        # on_sample(arm, snapshot) -> /joint_states with the arm's joint names after each poll.
        self.on_change: Callable[[Arm], None] = lambda arm: None
        self.on_sample: Callable[[Arm, Snapshot], None] = lambda arm, snap: None
        for arm, driver in zip(self.arms, self.drivers):
            driver.on_change = (lambda a=arm: self.on_change(a))
            driver.on_sample = (lambda snap, a=arm: self.on_sample(a, snap))

    @classmethod
    def build(cls, config: ManualConfig, hosts: Mapping[str, str], limits: Limits,
              make_driver: Callable[[Arm, ManualConfig], ArmDriver]) -> "CellDriver":
        """One driver per arm (plan_arms: the groups by resolved host), made by `make_driver(arm, its config)`."""
        arms = plan_arms(config, hosts)
        return cls(config, arms, [make_driver(arm, arm.config(config)) for arm in arms], limits)

    # ================================================================ lifecycle
    def start(self) -> None:
        for d in self.drivers:
            d.start()

    def shutdown(self) -> None:
        """Every driver shuts down at once (each stops its arm and lets its clients go, bounded in time)."""
        self._each(lambda d: d.shutdown())

    def _each(self, fn: Callable[[ArmDriver], object]) -> list[object]:
        """fn on every driver in parallel; the results in arm order (an exception is a result too)."""
        if len(self.drivers) == 1:
            return [fn(self.drivers[0])]
        results: list[object] = [None] * len(self.drivers)

        def run(i: int, d: ArmDriver) -> None:
            try:
                results[i] = fn(d)
            except Exception as e:  # noqa: BLE001 - reported by the caller, never lost in a thread
                results[i] = e

        threads = [threading.Thread(target=run, args=(i, d), name=f"arm-{d.host}", daemon=True)
                   for i, d in enumerate(self.drivers)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        return results

    # ================================================================ routing
    def _unknown_group(self, group: str) -> Said:
        return unknown_group(group, list(self.config.groups))

    def arm_of(self, group: str) -> Optional[Arm]:
        i = self._group_arm.get(group)
        return None if i is None else self.arms[i]

    def driver_of(self, group: str) -> Optional[ArmDriver]:
        i = self._group_arm.get(group)
        return None if i is None else self.drivers[i]

    def driver_of_tool(self, tool: str) -> Optional[ArmDriver]:
        i = self._tool_arm.get(tool)
        return None if i is None else self.drivers[i]

    # ================================================================ services
    def groups(self) -> tuple[list[Group], list[tuple[str, list[str], str]], Limits]:
        """The cell's groups, its tools as (name, action names, group), and the limits (the same on every arm)."""
        tools = [(t.name, list(t.actions), t.group) for t in self.config.tools.values()]
        return list(self.config.groups.values()), tools, self.limits

    def get_pose(self, group: str) -> tuple[bool, str, list[float], list[float]]:
        d = self.driver_of(group)
        if d is None:
            return False, self._unknown_group(group), [], []
        return d.get_pose(group)

    def move_named(self, group: str, name: str, speed: float = 0.0, acceleration: float = 0.0) -> tuple[bool, str]:
        d = self.driver_of(group)
        return (False, self._unknown_group(group)) if d is None else d.move_named(group, name, speed, acceleration)

    def move_relative(self, group: str, offset: Sequence[float], frame: str, speed: float = 0.0,
                      acceleration: float = 0.0) -> tuple[bool, str]:
        d = self.driver_of(group)
        return ((False, self._unknown_group(group)) if d is None
                else d.move_relative(group, offset, frame, speed, acceleration))

    def move_pose(self, group: str, pose: Sequence[float], speed: float = 0.0,
                  acceleration: float = 0.0) -> tuple[bool, str]:
        d = self.driver_of(group)
        return (False, self._unknown_group(group)) if d is None else d.move_pose(group, pose, speed, acceleration)

    def preview_move(self, group: str, kind: str, name: str = "", offset: Sequence[float] = (), frame: str = "",
                     pose: Sequence[float] = ()) -> tuple[bool, str, list[str], list[float], list[float]]:
        """Where a move of the group would take its arm (ManualDriver.preview_move): (reachable, message, joint
        names, joint positions, TCP pose)."""
        d = self.driver_of(group)
        if d is None:
            return False, self._unknown_group(group), [], [], []
        return d.preview_move(group, kind, name, offset, frame, pose)

    def tool_action(self, tool: str, action: str) -> tuple[bool, str]:
        d = self.driver_of_tool(tool)
        if d is None:
            return False, unknown_tool(tool, list(self.config.tools))
        return d.tool_action(tool, action)

    def stop(self) -> tuple[bool, str]:
        """Stop every arm; answers once every driver answered (each within ~1 s: at standstill, or unreachable).
        Success only when every arm confirmed; otherwise the message names the arms that did not."""
        results = self._each(lambda d: d.stop())
        if len(results) == 1 and not isinstance(results[0], Exception):
            return results[0]  # type: ignore[return-value]
        failed: list[Said] = []
        stopped: list[str] = []
        for arm, r in zip(self.arms, results):
            label = ", ".join(arm.groups)
            if isinstance(r, Exception):
                failed.append(say("manual.stop_failed", "{arms}: the stop failed ({error})", arms=label, error=r))
            elif r[0]:  # type: ignore[index]
                stopped.append(label)
            else:
                failed.append(say("manual.stop_not_confirmed", "{arms}: {why}", arms=label, why=r[1]))  # type: ignore[index]
        if not failed:
            return True, say("manual.stopped", "stopped")
        if len(failed) > 1:  # (several arms that did not stop: in English, joined)
            return False, "; ".join(failed) + (f" ({', '.join(stopped)} stopped)" if stopped else "")
        if stopped:
            return False, say("manual.stop_partly", "{failed} ({arms} stopped)", failed=failed[0],
                              arms=", ".join(stopped))
        return False, failed[0]

    # ================================================================ jogging
    def jog(self, group: str, mode: str, axis: int, direction: int, speed: float, frame: str = "base",
            age_s: Optional[float] = None, press: int = 0) -> None:
        """One JogCommand to its group's arm (age_s: how long ago the BFF let it through, None: unknown; press: the
        page's number for this press). A group no arm has: refused on every arm (a release, direction 0, stops
        whatever jogs)."""
        d = self.driver_of(group)
        if d is not None:
            d.jog(group, mode, axis, direction, speed, frame, age_s, press)
            return
        for d in self.drivers:
            if direction == 0:
                d.jog(group, mode, axis, direction, speed, frame)
            else:
                d.refuse_jog(self._unknown_group(group))

    # ================================================================ state
    def state(self, group: str) -> DriverState:
        """The state of the group's arm, for /cell/manual/<group>/state (motion_group: the group)."""
        d = self.driver_of(group)
        if d is None:
            raise KeyError(self._unknown_group(group))
        return replace(d.state(), motion_group=group)

    def tcp_pose(self, group: str) -> Optional[tuple[float, ...]]:
        """The group's arm's TCP pose for /cell/manual/<group>/tcp_pose; None while its controller is unreachable."""
        d = self.driver_of(group)
        if d is None or not d.connected:
            return None
        pose = d.snapshot().tcp_pose
        return tuple(pose) if len(pose) == 6 else None
