"""The routines feature without ROS: record, save, list, rename, delete, run and stop, with the log. Each method
answers (success, message[, value]) the way the services do; refusals never raise."""
from __future__ import annotations

import math
import threading
from typing import Optional, Sequence

from .config import RoutinesConfig
from .log import LogBook
from .model import (ACTION, POSE, Routine, RoutineError, Step, check_group, check_name, check_tool_action,
                    checked, format_pose, runnable_problem)
from .runner import Robot, Runner
from .store import RoutineStore


def _steps_text(n: int) -> str:
    return f"{n} step{'s' if n != 1 else ''}"


def _title(word: str) -> str:
    return word[:1].upper() + word[1:]


class Routines:
    def __init__(self, config: RoutinesConfig, store: RoutineStore, robot: Robot, log: LogBook,
                 runner: Optional[Runner] = None) -> None:
        self.config = config
        self.store = store
        self.robot = robot
        self.log = log
        self.runner = runner or Runner(robot, log, config.speed, config.acceleration)
        self._files = threading.Lock()   # one file operation at a time (rename's check-then-link, save's check)

    # ---------------------------------------------------------------- list
    def list(self) -> tuple[bool, str, list[Routine]]:
        with self._files:
            try:
                routines = self.store.list()
            except RoutineError as e:
                return False, str(e), []
        out = [r if r.error else Routine(r.name, r.group, r.tool, r.steps, r.modified,
                                         runnable_problem(self.config, r)) for r in routines]
        return True, f"{len(out)} routine{'s' if len(out) != 1 else ''}", out

    # ---------------------------------------------------------------- record
    def record(self, group: str, tool: str, kind: str, action: str) -> tuple[bool, str, Optional[Step]]:
        """One step for the page's draft: the arm's current pose, or a checked tool action. Nothing is stored."""
        try:
            if kind == POSE:
                check_group(self.config, group)
                ok, why, joints, tcp = self.robot.get_pose(group)
                if not ok:
                    raise RoutineError(f"cannot read the pose: {why}")
                if len(tcp) != 6 or not all(math.isfinite(v) for v in tcp):
                    raise RoutineError("the robot driver answered no TCP pose")
                step = Step(POSE, tuple(float(v) for v in tcp), tuple(float(v) for v in joints))
                text = f"Pose recorded: {format_pose(step.pose)}"
            elif kind == ACTION:
                if group:
                    check_group(self.config, group)
                check_tool_action(self.config, tool, action, group)
                step = Step(ACTION, tool=tool, action=action)
                text = f"{_title(tool)} {action} recorded"
            else:
                raise RoutineError(f"unknown step kind {kind!r} (pose or action)")
        except RoutineError as e:
            return False, str(e), None
        except Exception as e:  # the robot interface should answer, not raise
            return False, f"cannot read the pose: the robot driver call failed: {e}", None
        self.log.info(text)
        return True, text, step

    # ---------------------------------------------------------------- files
    def save(self, name: str, group: str, tool: str, steps: Sequence[Step], overwrite: bool) -> tuple[bool, str]:
        try:
            routine = checked(self.config, name, group, tool, steps)
            with self._files:
                if overwrite and self.runner.running() == name:
                    raise RoutineError(f"routine {name} is running: stop it first")
                replaced = self.store.save(routine, overwrite)
        except RoutineError as e:
            return False, str(e)
        what = "replaced" if replaced else "saved"
        self.log.info(f"Routine {name} {what} ({_steps_text(len(routine.steps))})")
        return True, f"routine {name} {what} ({_steps_text(len(routine.steps))})"

    def rename(self, name: str, new_name: str) -> tuple[bool, str]:
        try:
            check_name(name)
            check_name(new_name)
            with self._files:
                if self.runner.running() == name:
                    raise RoutineError(f"routine {name} is running: stop it first")
                self.store.rename(name, new_name)
        except RoutineError as e:
            return False, str(e)
        self.log.info(f"Routine {name} renamed to {new_name}")
        return True, f"routine {name} renamed to {new_name}"

    def delete(self, name: str) -> tuple[bool, str]:
        try:
            check_name(name)
            with self._files:
                if self.runner.running() == name:
                    raise RoutineError(f"routine {name} is running: stop it first")
                self.store.delete(name)
        except RoutineError as e:
            return False, str(e)
        self.log.info(f"Routine {name} deleted")
        return True, f"routine {name} deleted"

    # ---------------------------------------------------------------- run
    def run(self, name: str) -> tuple[bool, str]:
        """Run a saved routine (read from its file now); answers when it ends."""
        try:
            check_name(name)
            with self._files:
                routine = self.store.read(name)
            if routine.error:
                raise RoutineError(f"routine {name} cannot run: {routine.error}")
            problem = runnable_problem(self.config, routine)
            if problem:
                raise RoutineError(f"routine {name} {problem}")
        except RoutineError as e:
            self.log.warning(f"Run refused: {e}")
            return False, str(e)
        return self.runner.run(routine)

    def stop(self) -> tuple[bool, str]:
        return self.runner.stop()
