"""The routines feature without ROS: record, save, list, rename, delete, run and stop, with the log. Each method
answers (success, message[, value]) the way the services do; refusals never raise."""
from __future__ import annotations

import math
import threading
from typing import Optional, Sequence

from .config import RoutinesConfig
from .log import LogBook
from .model import (ACTION, POSE, Routine, RoutineError, Step, check_group, check_name, check_tool_action,
                    checked, format_pose, runnable_problem, said_of, step_kind_problem)
from ..said import say
from .runner import Robot, Runner, busy, driver_failed, steps_text
from .store import RoutineStore


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
        return True, (say("routines.count_one", "{count} routine", count=len(out)) if len(out) == 1 else
                      say("routines.count", "{count} routines", count=len(out))), out

    # ---------------------------------------------------------------- record
    def record(self, group: str, tool: str, kind: str, action: str) -> tuple[bool, str, Optional[Step]]:
        """One step for the page's draft: the arm's current pose, or a checked tool action. Nothing is stored."""
        try:
            if kind == POSE:
                check_group(self.config, group)
                ok, why, joints, tcp = self.robot.get_pose(group)
                if not ok:
                    raise RoutineError(say("routines.no_pose", "cannot read the pose: {why}", why=why))
                if len(tcp) != 6 or not all(math.isfinite(v) for v in tcp):
                    raise RoutineError(say("routines.no_tcp", "the robot driver answered no TCP pose"))
                step = Step(POSE, tuple(float(v) for v in tcp), tuple(float(v) for v in joints))
                text = say("routines.pose_recorded", "Pose recorded: {pose}", pose=format_pose(step.pose))
            elif kind == ACTION:
                if group:
                    check_group(self.config, group)
                check_tool_action(self.config, tool, action, group)
                step = Step(ACTION, tool=tool, action=action)
                text = say("routines.action_recorded", "{tool} {action} recorded", tool=_title(tool), action=action)
            else:
                raise RoutineError(step_kind_problem(kind))
        except RoutineError as e:
            return False, said_of(e), None
        except Exception as e:  # the robot interface should answer, not raise
            return False, say("routines.no_pose", "cannot read the pose: {why}", why=driver_failed(e)), None
        self.log.info(text)
        return True, text, step

    # ---------------------------------------------------------------- files
    def save(self, name: str, group: str, tool: str, steps: Sequence[Step], overwrite: bool) -> tuple[bool, str]:
        try:
            routine = checked(self.config, name, group, tool, steps)
            with self._files:
                if overwrite and self.runner.running() == name:
                    raise RoutineError(busy(name))
                replaced = self.store.save(routine, overwrite)
        except RoutineError as e:
            return False, said_of(e)
        steps = steps_text(len(routine.steps))
        if replaced:
            self.log.info(say("routines.replaced_log", "Routine {name} replaced ({steps})", name=name, steps=steps))
            return True, say("routines.replaced", "routine {name} replaced ({steps})", name=name, steps=steps)
        self.log.info(say("routines.saved_log", "Routine {name} saved ({steps})", name=name, steps=steps))
        return True, say("routines.saved", "routine {name} saved ({steps})", name=name, steps=steps)

    def rename(self, name: str, new_name: str) -> tuple[bool, str]:
        try:
            check_name(name)
            check_name(new_name)
            with self._files:
                if self.runner.running() == name:
                    raise RoutineError(busy(name))
                self.store.rename(name, new_name)
        except RoutineError as e:
            return False, said_of(e)
        self.log.info(say("routines.renamed_log", "Routine {name} renamed to {new_name}", name=name, new_name=new_name))
        return True, say("routines.renamed", "routine {name} renamed to {new_name}", name=name, new_name=new_name)

    def delete(self, name: str) -> tuple[bool, str]:
        try:
            check_name(name)
            with self._files:
                if self.runner.running() == name:
                    raise RoutineError(busy(name))
                self.store.delete(name)
        except RoutineError as e:
            return False, said_of(e)
        self.log.info(say("routines.deleted_log", "Routine {name} deleted", name=name))
        return True, say("routines.deleted", "routine {name} deleted", name=name)

    # ---------------------------------------------------------------- run
    def run(self, name: str) -> tuple[bool, str]:
        """Run a saved routine (read from its file now); answers when it ends."""
        try:
            check_name(name)
            with self._files:
                routine = self.store.read(name)
            if routine.error:
                raise RoutineError(say("routines.cannot_run", "routine {name} cannot run: {error}", name=name,
                                       error=routine.error))
            problem = runnable_problem(self.config, routine)
            if problem:
                raise RoutineError(say("routines.not_runnable_named", "routine {name} {problem}", name=name,
                                       problem=problem))
        except RoutineError as e:
            self.log.warning(say("routines.run_refused", "Run refused: {why}", why=said_of(e)))
            return False, said_of(e)
        return self.runner.run(routine)

    def stop(self) -> tuple[bool, str]:
        return self.runner.stop()
