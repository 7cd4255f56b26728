"""Runs a routine's steps through the robot driver, one run at a time: pose steps as linear moves (move_pose),
action steps as tool actions. Stop ends the run at once: no further step starts, and the driver's stop ends the
step under way (the driver answers that call with "stopped").

The robot is injected (the node passes ROS service proxies, the tests a fake), so this runs without ROS."""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, replace
from typing import Callable, Protocol, Sequence

from ..said import Said, say
from .log import LogBook
from .model import POSE, Routine, Step, describe

IDLE, RUNNING, STOPPING = "idle", "running", "stopping"
STOPPED = "stopped"
STOP_RETRY_S = 0.5      # stop again when the run has not ended this long after the driver's stop
STOP_GIVE_UP_S = 3.0


def busy(name: str) -> Said:
    return say("routines.busy", "routine {name} is running: stop it first", name=name)


def stopped(name: str) -> Said:
    return say("routines.stopped", "routine {name} stopped", name=name)


def driver_failed(e: object) -> Said:
    return say("routines.driver_failed", "the robot driver call failed: {error}", error=e)


def steps_text(n: int) -> Said:
    return (say("routines.steps_one", "{count} step", count=n) if n == 1 else
            say("routines.steps", "{count} steps", count=n))


class Robot(Protocol):
    """The robot driver's services (/cell/manual/*) as the routines need them; each answers (success, message)."""

    def get_pose(self, group: str) -> tuple[bool, str, list[float], list[float]]: ...
    def move_pose(self, group: str, pose: Sequence[float], speed: float, acceleration: float) -> tuple[bool, str]: ...
    def tool(self, tool: str, action: str) -> tuple[bool, str]: ...
    def stop(self) -> tuple[bool, str]: ...


@dataclass(frozen=True)
class RunState:
    name: str = ""
    state: str = IDLE
    step: int = 0         # 1-based, 0: none
    total: int = 0
    message: str = ""


class Runner:
    def __init__(self, robot: Robot, log: LogBook, speed: float = 0.0, acceleration: float = 0.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.robot = robot
        self.log = log
        self.speed = speed
        self.acceleration = acceleration
        self.clock = clock
        self._lock = threading.Lock()
        self._state = RunState()
        self._stop_requested = False
        self._ended = threading.Event()
        self._ended.set()
        # The node sets this: publish the state. Called under the lock, so states go out in order.
        self.on_state: Callable[[RunState], None] = lambda state: None

    def state(self) -> RunState:
        with self._lock:
            return self._state

    def running(self) -> str:
        """The name of the routine running (or stopping), "" when idle."""
        with self._lock:
            return self._state.name if self._state.state != IDLE else ""

    def _set(self, **changes: object) -> None:
        # Under self._lock.
        self._state = replace(self._state, **changes)
        self.on_state(self._state)

    # ---------------------------------------------------------------- run
    def run(self, routine: Routine) -> tuple[bool, str]:
        """Run every step in order; answers when the run ends: done, stopped, or the failing step's message."""
        name, steps, total = routine.name, routine.steps, len(routine.steps)
        with self._lock:
            if self._state.state != IDLE:
                why = busy(self._state.name)
                self.log.warning(say("routines.run_refused", "Run refused: {why}", why=why))
                return False, why
            self._stop_requested = False
            self._ended.clear()
            self._set(name=name, state=RUNNING, step=0, total=total,
                      message=say("routines.started", "routine {name} started", name=name))
            self.log.info(say("routines.started_log", "Routine {name} started ({steps}, group {group})", name=name,
                              steps=steps_text(total), group=routine.group))
        ok, message = True, say("routines.done", "routine {name} done", name=name)
        try:
            for i, step in enumerate(steps, 1):
                with self._lock:
                    # Checked under the lock that stop() sets the flag under: no step starts after a stop.
                    if self._stop_requested:
                        ok, message = False, STOPPED
                        break
                    self._set(step=i, message=say("routines.step", "step {step} of {total}: {what}", step=i,
                                                  total=total, what=describe(step)))
                done, why = self._do(routine, step)
                if self._stop_requested or (not done and why == STOPPED):
                    # Ours, or the driver was stopped by someone else (the page's "Stop robot"): the run is over.
                    ok, message = False, STOPPED
                    break
                if not done:
                    ok, message = False, say("routines.step_failed", "step {step} of {total} ({what}) failed: {why}",
                                             step=i, total=total, what=describe(step), why=why)
                    break
                self.log.info(say("routines.step_reached", "Step {step} of {total} reached: {what}", step=i,
                                  total=total, what=describe(step)) if step.kind == POSE else
                              say("routines.step_done", "Step {step} of {total} done: {what}", step=i, total=total,
                                  what=describe(step)))
        except Exception as e:  # never leave the runner "running" behind an unexpected error
            ok, message = False, say("routines.failed", "routine {name} failed: {error}", name=name, error=e)
        with self._lock:
            step = self._state.step
            if ok:
                self.log.info(say("routines.done_log", "Routine {name} done", name=name))
            elif message == STOPPED:
                self.log.warning(say("routines.stopped_at", "Routine {name} stopped at step {step} of {total}",
                                     name=name, step=step, total=total))
            else:
                self.log.error(say("routines.failed_log", "Routine {name} failed: {why}", name=name, why=message))
            self._set(state=IDLE, step=0, message=message if message != STOPPED else stopped(name))
            self._ended.set()
        return ok, message

    def _do(self, routine: Routine, step: Step) -> tuple[bool, str]:
        try:
            if step.kind == POSE:
                return self.robot.move_pose(routine.group, list(step.pose), self.speed, self.acceleration)
            return self.robot.tool(step.tool or routine.tool, step.action)
        except Exception as e:  # the robot interface should answer, not raise; a failed call fails the step
            return False, driver_failed(e)

    # ---------------------------------------------------------------- stop
    def stop(self) -> tuple[bool, str]:
        """End the run now: no further step, and the driver stops the one under way. Answers once the run ended."""
        with self._lock:
            if self._state.state == IDLE:
                return True, say("routines.none_running", "no routine is running")
            self._stop_requested = True
            name, total = self._state.name, self._state.total
            self._set(state=STOPPING, message=say("routines.stopping", "stopping routine {name}", name=name))
        deadline = self.clock() + STOP_GIVE_UP_S
        robot_ok, robot_why = True, ""
        while True:
            # Again while the run has not ended: a step call sent just before our flag was set can reach the
            # driver after its stop did (two connections) and start a move there.
            try:
                robot_ok, robot_why = self.robot.stop()
            except Exception as e:
                robot_ok, robot_why = False, driver_failed(e)
            if self._ended.wait(STOP_RETRY_S) or self.clock() > deadline:
                break
        if not self._ended.is_set():
            return False, say("routines.stop_timeout", "routine {name} did not end within {seconds} s of the stop: "
                              "{why}", name=name, seconds=f"{STOP_GIVE_UP_S:g}", why=robot_why)
        if not robot_ok:
            return False, say("routines.stop_unconfirmed", "routine {name} stopped; the robot driver did not confirm: "
                              "{why}", name=name, why=robot_why)
        return True, stopped(name)
