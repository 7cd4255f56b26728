"""Runs the process: operations in order, step by step, cycling; pause at a step's end, resume, stop at once.

No ROS here: the robot driver, the routines node, topics and the clock are injected (the action server wires them to
ROS; the tests use fakes). One run at a time: `begin` reserves the executor, `run` executes in the caller's thread
(the action server's worker), and `stop`, `pause`, `resume` and `abort` come from other threads.

Rules:
- A step's result is the driver's (or routine node's) answer; a failure ends the run in state `error` with that
  message, after a driver stop so the arm stands still.
- Stop never waits for the step: it asks the driver to stop (and the routines node, if a routine runs) and the
  interrupted step's answer ("stopped") ends the run in `idle`. A move that reaches the driver just after the stop
  is stopped again (the stop repeats while a motion call is still out).
- Pause takes effect between steps: `pausing` until the current step ends, then `paused` with the arm held by the
  driver. A routine has no pause of its own: pausing stops it, and it runs again from its start on resume.
- Dry run: every step is logged and shown for `dry_run_step_s`, without any robot, tool, routine or topic call.
- Cycle times: a cycle's active time excludes the time spent `paused` (from the hold between two steps to the
  resume); its elapsed time includes it. `pausing` is not paused time: the step is still running.
- Every line it logs, its step texts and its results are said with a code (cell_nodes.said): the app says them in
  the user's language.
"""
from __future__ import annotations

import dataclasses
import threading
from dataclasses import dataclass
from typing import Any, Callable, Optional, Protocol, Sequence

from cell_nodes.said import Said, say

from .conditions import ConditionError, describe_value, field_value, holds
from .config import (MoveNamed, MovePose, MoveRelative, ProcessConfig, Routine, Step, Tool, WaitTime, WaitTopic)
from .steps import CONDITION_SIGNS, describe, resolve_pose

IDLE, RUNNING, PAUSING, PAUSED, STOPPING, ERROR = "idle", "running", "pausing", "paused", "stopping", "error"
ACTIVE_STATES = (RUNNING, PAUSING, PAUSED, STOPPING)
POLL_S = 0.02           # how often waits look at stop/pause requests
RESTOP_S = 0.5          # a motion call still out this long after a stop gets another stop
STOP_WAIT_S = 3.0       # how long a stop keeps re-stopping a motion call that does not return


class Robot(Protocol):
    """The robot driver's services (/cell/manual/*) and the routines node's (/cell/routines/*): (success, message)."""

    def move_named(self, group: str, name: str, speed: float, acceleration: float) -> tuple[bool, str]: ...

    def move_relative(self, group: str, offset: Sequence[float], frame: str, speed: float,
                      acceleration: float) -> tuple[bool, str]: ...

    def move_pose(self, group: str, pose: Sequence[float], speed: float, acceleration: float) -> tuple[bool, str]: ...

    def tool(self, tool: str, action: str) -> tuple[bool, str]: ...

    def stop(self) -> tuple[bool, str]: ...

    def run_routine(self, name: str) -> tuple[bool, str]: ...

    def stop_routine(self) -> tuple[bool, str]: ...


class Topics(Protocol):
    def watch(self, topic: str, on_message: Callable[[Any], None]) -> Callable[[], None]:
        """Call on_message with every message of `topic` until the returned function is called."""


class Clock(Protocol):
    def now(self) -> float: ...

    def sleep(self, seconds: float) -> None: ...


@dataclass(frozen=True)
class RunRequest:
    operation: int = -1     # -1: every operation in order; else only this one
    cycles: int = 1         # 0: until stopped
    dry_run: bool = False
    first_cycle: int = 1    # the first cycle's number (pose tables)


@dataclass
class Progress:
    """What a run is doing now (the action's feedback)."""
    state: str = IDLE
    operation: int = -1
    step_index: int = -1
    step_count: int = 0
    step: str = ""
    cycle: int = 0
    cycles_done: int = 0
    cycle_start: float = 0.0
    last_cycle_s: float = 0.0           # the last completed cycle's active time (paused time excluded)
    message: str = ""
    cycle_paused_s: float = 0.0         # paused time of the current cycle so far (pauses that ended)
    paused_since: float = 0.0           # when the pause going on began (clock time), 0 none
    last_cycle_elapsed_s: float = 0.0   # the last completed cycle from start to end, paused time included

    def cycle_times(self, now: float) -> tuple[float, float]:
        """(active, elapsed) seconds of the current cycle at `now`; (0, 0) without a cycle start."""
        if not self.cycle_start:
            return 0.0, 0.0
        elapsed = max(0.0, now - self.cycle_start)
        paused = self.cycle_paused_s + (max(0.0, now - self.paused_since) if self.paused_since else 0.0)
        return max(0.0, elapsed - paused), elapsed


@dataclass(frozen=True)
class RunResult:
    success: bool
    message: str
    state: str              # IDLE (done or stopped) or ERROR
    stopped: bool = False   # ended by stop (not by its end or an error)
    cycles_done: int = 0
    last_cycle_s: float = 0.0
    operation: int = -1
    step_index: int = -1
    step: str = ""
    last_cycle_elapsed_s: float = 0.0


class _Stopped(Exception):
    pass


class _Failed(Exception):
    pass


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def _count(n: int, word: str) -> Said:
    """"1 cycle", "3 operations", "2 times": the app picks the plural form of the user's language."""
    return say(f"process.count_{word}", _plural(n, word), count=n)


BY_OPERATOR = say("process.reason_operator", "stopped by the operator")
DRY_SUFFIX = say("process.dry_suffix", " (dry run: no robot motion)")


def _reason(e: BaseException) -> str:
    """An exception's message, as said (str(e) would drop its code)."""
    return e.args[0] if e.args and isinstance(e.args[0], str) else str(e)


class Executor:
    def __init__(self, config: ProcessConfig, robot: Robot, clock: Clock, topics: Optional[Topics] = None,
                 on_progress: Callable[[Progress], None] = lambda p: None,
                 on_log: Callable[[str, str], None] = lambda level, text: None) -> None:
        self.config = config
        self.robot = robot
        self.clock = clock
        self.topics = topics
        self.on_progress = on_progress
        self.on_log = on_log
        self._lock = threading.Lock()
        self._emit_lock = threading.RLock()   # progress goes out in the order it changed
        self._p = Progress()
        self._active = False
        self._dry = False
        self._pause = False
        self._cancel: Optional[tuple[str, str]] = None   # (end state, message) once a stop or abort is asked
        self._in_routine = False
        self._routine_paused = False     # the pause stopped the running routine: run it again
        self._calls_out = 0              # robot motion calls in progress (the stop re-stops them)
        self._stop_done = threading.Event()  # the stop's driver call has come back: the run may end
        self._stop_done.set()

    # ------------------------------------------------------------------------------------------- queries
    @property
    def active(self) -> bool:
        with self._lock:
            return self._active

    def progress(self) -> Progress:
        with self._lock:
            return dataclasses.replace(self._p)

    def refusal(self, req: RunRequest) -> Optional[str]:
        """Why this request cannot start now, or None."""
        n = len(self.config.operations)
        if self._active:
            what = "paused: resume or stop it" if self._p.state == PAUSED else "running: stop it first"
            return f"the process is already {what}"
        if req.operation < -1 or req.operation >= n:
            names = ", ".join(f"{i} {o.name}" for i, o in enumerate(self.config.operations))
            return f"no operation {req.operation} (the process has {n}: {names})"
        if req.cycles < 0:
            return f"cycles must be 0 (until stopped) or more, got {req.cycles}"
        return None

    # ------------------------------------------------------------------------------------------- events
    def _apply(self, **changes: Any) -> None:
        """Caller holds _lock. A run's state follows the requests: a stop wins over everything, a pending pause
        turns `running` into `pausing` (so a step starting just after a pause request does not hide it)."""
        st = changes.get("state")
        if self._active and st in (RUNNING, PAUSING, PAUSED):
            if self._cancel is not None:
                changes["state"] = STOPPING
            elif st == RUNNING and self._pause:
                changes["state"] = PAUSING
        for k, v in changes.items():
            setattr(self._p, k, v)

    def _emit(self, **changes: Any) -> None:
        """Apply changes and send the progress as it is now (the snapshot is taken in order under _emit_lock)."""
        with self._emit_lock:
            with self._lock:
                self._apply(**changes)
                snap = dataclasses.replace(self._p)
            self.on_progress(snap)

    def _log(self, level: str, text: str) -> None:
        with self._emit_lock:
            self.on_log(level, text)

    # ------------------------------------------------------------------------------------------- commands
    def begin(self, req: RunRequest, config: Optional[ProcessConfig] = None) -> Optional[str]:
        """Reserve the executor for `req` (then call run); returns why not, or None. `config`: the process as it is
        now (the parameter values re-read at each start; the operations are the cell file's, so the same), adopted
        only when the run is accepted: a running or paused run keeps the values it started with."""
        with self._lock:
            why = self.refusal(req)
            if why is None:
                if config is not None:
                    self.config = config
                self._active, self._dry, self._pause, self._cancel = True, req.dry_run, False, None
                self._routine_paused = False
        return why

    def execute(self, req: RunRequest) -> RunResult:
        """begin + run, for callers without a separate accept step."""
        why = self.begin(req)
        if why is not None:
            self._log("warning", say("process.start_refused", "Start refused: {reason}", reason=why))
            return RunResult(False, why, self._p.state if self._active else IDLE)
        return self.run(req)

    def stop(self, message: str = BY_OPERATOR) -> tuple[bool, str]:
        """End the run now: the arm is stopped (driver stop), the step is not waited for. Answers after the stop."""
        return self._end_now(IDLE, message, "Stop")

    def abort(self, message: str) -> tuple[bool, str]:
        """Like stop, but the run ends in `error` with `message` (e.g. the cell went into alarm)."""
        return self._end_now(ERROR, message, "Abort")

    def _end_now(self, end_state: str, message: str, what: str) -> tuple[bool, str]:
        with self._lock:
            if not self._active:
                return True, "the process is not running"
            first = self._cancel is None
            if first:
                self._cancel = (end_state, message)
                self._stop_done.clear()
                self._apply(state=STOPPING)
            dry, routine = self._dry, self._in_routine
        if not first:
            return True, "already stopping"
        try:
            return self._stop_robot(end_state, message, what, dry, routine)
        finally:
            self._stop_done.set()

    def _stop_robot(self, end_state: str, message: str, what: str, dry: bool, routine: bool) -> tuple[bool, str]:
        self._emit()
        self._log("warning" if end_state == IDLE else "error",
                  say(f"process.{what.lower()}", what + ": {reason}", reason=message))
        if dry:
            return True, "stopped (dry run: no robot motion to stop)"
        if routine:
            ok, msg = self._call(self.robot.stop_routine)
            if not ok:
                self._log("warning", say("process.routines_stop_failed", "the routines node's stop failed: {reason}",
                                         reason=msg))
        ok, msg = self._call(self.robot.stop)
        # A move that reached the driver just after our stop would run to its end: stop it again while it is out.
        t0 = last = self.clock.now()
        while self._calls() and self.clock.now() - t0 < STOP_WAIT_S:
            if self.clock.now() - last >= RESTOP_S:
                ok, msg = self._call(self.robot.stop)
                last = self.clock.now()
            self.clock.sleep(POLL_S)
        if not ok:
            self._log("error", say("process.driver_stop_failed", "the robot driver's stop failed: {reason}", reason=msg))
            return False, f"stopping the arm failed: {msg}"
        return True, "stopped"

    def pause(self) -> tuple[bool, str]:
        with self._lock:
            if not self._active:
                return False, "the process is not running"
            state = self._p.state
            if state == STOPPING:
                return False, "the process is stopping"
            if state in (PAUSING, PAUSED):
                return True, "already paused" if state == PAUSED else "already pausing: the current step finishes first"
            self._pause = True
            self._apply(state=PAUSING)
            routine = self._in_routine and not self._dry
            if routine:
                self._routine_paused = True
            step = self._p.step
        self._emit()
        if routine:
            self._log("info", say("process.pause_routine",
                                  "Pause: stopping the routine of '{step}' (it runs again from its start on resume)",
                                  step=step))
            ok, msg = self._call(self.robot.stop_routine)
            if not ok:
                self._log("warning", say("process.routines_stop_failed", "the routines node's stop failed: {reason}",
                                         reason=msg))
            return True, "pausing: the routine was stopped"
        self._log("info", say("process.pause", "Pause: '{step}' finishes first", step=step))
        return True, "pausing after the current step"

    def resume(self) -> tuple[bool, str]:
        with self._lock:
            if not self._active:
                return False, "the process is not running"
            state = self._p.state
            if state not in (PAUSING, PAUSED):
                return False, "the process is not paused" if state != STOPPING else "the process is stopping"
            self._pause = False
            if self._p.paused_since:   # the pause ends here: its time is not the cycle's active time
                self._p.cycle_paused_s += max(0.0, self.clock.now() - self._p.paused_since)
                self._p.paused_since = 0.0
            self._apply(state=RUNNING)
        self._emit()
        if state == PAUSING:
            self._log("info", say("process.resume_pausing", "Resume: pause cancelled, the run goes on"))
            return True, "pause cancelled: the run goes on"
        return True, "resumed"

    # ------------------------------------------------------------------------------------------- the run
    def run(self, req: RunRequest) -> RunResult:
        """Execute an accepted request (begin) to its end; blocks."""
        cfg = self.config
        ops = list(range(len(cfg.operations))) if req.operation < 0 else [req.operation]
        cycle = max(req.first_cycle, 1)
        done = 0
        dry = DRY_SUFFIX if req.dry_run else ""
        forever = say("process.until_stopped", "until stopped")
        if req.operation >= 0:
            times = say("process.once", "once") if req.cycles == 1 else (forever if req.cycles == 0 else
                                                                         _count(req.cycles, "time"))
            self._log("info", say("process.start_operation", "Start: operation '{operation}' {times}{dry}",
                                  operation=cfg.operations[req.operation].name, times=times, dry=dry))
        else:
            many = forever if req.cycles == 0 else _count(req.cycles, "cycle")
            self._log("info", say("process.start_cycles", "Start: {cycles} of {operations} from cycle {cycle}{dry}",
                                  cycles=many, operations=_count(len(ops), "operation"), cycle=cycle, dry=dry))
        self._emit(state=RUNNING, operation=-1, step_index=-1, step_count=0, step="", cycle=cycle, cycles_done=0,
                   cycle_start=self.clock.now(), cycle_paused_s=0.0, paused_since=0.0, message="running")
        try:
            while req.cycles == 0 or done < req.cycles:
                started = self.clock.now()
                self._emit(cycle=cycle, cycle_start=started, cycle_paused_s=0.0, paused_since=0.0)
                for oi in ops:
                    self._run_operation(oi, cycle, req.dry_run)
                done += 1
                if req.operation < 0:
                    # One change for the count and both times: a client saving them sees them together.
                    with self._lock:
                        active, elapsed = self._p.cycle_times(self.clock.now())
                    self._emit(cycles_done=done, last_cycle_s=active, last_cycle_elapsed_s=elapsed)
                    paused = say("process.with_pauses", " ({seconds} s with pauses)", seconds=f"{elapsed:.1f}") \
                        if elapsed - active >= 0.05 else ""
                    self._log("info", say("process.cycle_done", "Cycle {cycle} done in {seconds} s{paused}", cycle=cycle,
                                          seconds=f"{active:.1f}", paused=paused))
                else:
                    self._emit(cycles_done=done)
                cycle += 1
            if req.operation >= 0:
                name = cfg.operations[req.operation].name
                message = say("process.done_operation", "operation '{operation}' done", operation=name) \
                    if req.cycles == 1 else say("process.done_operation_times", "operation '{operation}' done {times}",
                                                operation=name, times=_count(done, "time"))
            else:
                message = say("process.done_cycles", "{cycles} done", cycles=_count(done, "cycle"))
            return self._finish(RunResult(True, message, IDLE, False, done, self._p.last_cycle_s,
                                          last_cycle_elapsed_s=self._p.last_cycle_elapsed_s), "info",
                                say("process.done", "Done: {result}", result=message))
        except _Stopped:
            # The interrupted step answers "stopped" as soon as the driver got the stop; the run ends (and the
            # action's result goes out) only once the driver reports the arm standing still.
            self._stop_done.wait(STOP_WAIT_S + 2.0)
            end_state, message = self._cancel or (IDLE, "stopped")
            how = "stopped" if end_state == IDLE else "error"
            text = say(f"process.{how}_during", how.capitalize() + " during '{step}': {reason}", step=self._p.step,
                       reason=message) if self._p.step else \
                say(f"process.{how}", how.capitalize() + ": {reason}", reason=message)
            p = self._p
            return self._finish(RunResult(False, message, end_state, end_state == IDLE, done, p.last_cycle_s,
                                          p.operation, p.step_index, p.step, p.last_cycle_elapsed_s),
                                "warning" if end_state == IDLE else "error", text)
        except _Failed as e:
            message = _reason(e)
            if not req.dry_run:
                ok, why = self._call(self.robot.stop)   # whatever failed, leave the arm standing still
                if not ok:
                    self._log("warning", say("process.driver_stop_failed", "the robot driver's stop failed: {reason}",
                                             reason=why))
            p = self._p
            return self._finish(RunResult(False, message, ERROR, False, done, p.last_cycle_s, p.operation,
                                          p.step_index, p.step, p.last_cycle_elapsed_s), "error",
                                say("process.error", "Error: {reason}", reason=message))

    def _finish(self, result: RunResult, level: str, text: str) -> RunResult:
        self._log(level, text)
        changes: dict[str, Any] = dict(state=result.state, message=result.message, cycles_done=result.cycles_done,
                                       paused_since=0.0)
        if result.state != ERROR:   # an error keeps showing where it happened
            changes.update(operation=-1, step_index=-1, step_count=0, step="")
        with self._emit_lock:
            with self._lock:
                self._active = False
                self._cancel = None
                self._pause = False
            self._emit(**changes)
        return result

    def _run_operation(self, oi: int, cycle: int, dry_run: bool) -> None:
        op = self.config.operations[oi]
        self._log("info", say("process.operation", "Operation '{operation}' (cycle {cycle})", operation=op.name,
                              cycle=cycle))
        for si, step in enumerate(op.steps):
            text = describe(step, cycle, self.config.poses)
            while True:
                self._checkpoint(text)
                self._emit(state=RUNNING, operation=oi, step_index=si, step_count=len(op.steps), step=text)
                self._log("info", say("process.dry_step", "Dry run: {step}", step=text) if dry_run else text)
                ok, message = self._do(step, cycle, dry_run)
                with self._lock:
                    cancelled = self._cancel is not None
                    rerun = not ok and isinstance(step, Routine) and self._routine_paused
                    self._routine_paused = False
                if cancelled:
                    raise _Stopped()
                if rerun:
                    self._log("info", say("process.routine_rerun", "Routine {name} was stopped by the pause: it runs again "
                                          "on resume", name=step.name))
                    continue
                if not ok:
                    raise _Failed(say("process.step_failed", "{step} failed: {reason}", step=text, reason=message))
                break
        self._log("info", say("process.operation_done", "Operation '{operation}' done", operation=op.name))

    def _checkpoint(self, next_text: str) -> None:
        """Between two steps: end here if stopped; hold here while a pause is asked for."""
        with self._lock:
            if self._cancel is not None:
                raise _Stopped()
            if not self._pause:
                return
            self._apply(state=PAUSED, paused_since=self.clock.now())
            after = self._p.step
        self._emit()
        self._log("info", say("process.paused_after", "Paused after '{after}'; next: '{next}'", after=after, next=next_text)
                  if after else say("process.paused", "Paused; next: '{next}'", next=next_text))
        while True:
            with self._lock:
                if self._cancel is not None:
                    raise _Stopped()
                if not self._pause:
                    break
            self.clock.sleep(POLL_S)
        self._log("info", say("process.resumed", "Resumed: next '{next}'", next=next_text))

    # ------------------------------------------------------------------------------------------- steps
    def _calls(self) -> int:
        with self._lock:
            return self._calls_out

    def _call(self, fn: Callable[..., tuple[bool, str]], *args: Any) -> tuple[bool, str]:
        """A robot call: never raises (a dead service is a failed step, not a crashed node)."""
        try:
            ok, message = fn(*args)
            return bool(ok), str(message)
        except Exception as e:  # noqa: BLE001 - whatever the transport raises becomes the step's message
            return False, f"{type(e).__name__}: {e}" if not str(e) else str(e)

    def _motion(self, fn: Callable[..., tuple[bool, str]], *args: Any) -> tuple[bool, str]:
        with self._lock:
            if self._cancel is not None:   # a stop came in since the checkpoint: do not start the move
                return False, "stopped"
            self._calls_out += 1
        try:
            return self._call(fn, *args)
        finally:
            with self._lock:
                self._calls_out -= 1

    def _do(self, step: Step, cycle: int, dry_run: bool) -> tuple[bool, str]:
        cfg = self.config
        if dry_run:
            return self._wait(cfg.dry_run_step_s)
        if isinstance(step, MoveNamed):
            m = step.motion
            return self._motion(self.robot.move_named, m.group, step.name, m.speed or cfg.joint_speed,
                                m.acceleration or cfg.joint_acceleration)
        if isinstance(step, MoveRelative):
            m = step.motion
            return self._motion(self.robot.move_relative, m.group, list(step.offset), step.frame,
                                m.speed or cfg.tcp_speed, m.acceleration or cfg.tcp_acceleration)
        if isinstance(step, MovePose):
            m = step.motion
            return self._motion(self.robot.move_pose, m.group, resolve_pose(step, cycle, cfg.poses),
                                m.speed or cfg.tcp_speed, m.acceleration or cfg.tcp_acceleration)
        if isinstance(step, Tool):
            return self._motion(self.robot.tool, step.tool, step.action)
        if isinstance(step, WaitTime):
            return self._wait(step.seconds)
        if isinstance(step, WaitTopic):
            return self._wait_topic(step)
        if isinstance(step, Routine):
            with self._lock:
                self._in_routine = True
            try:
                return self._motion(self.robot.run_routine, step.name)
            finally:
                with self._lock:
                    self._in_routine = False
        return False, f"unknown step {step!r}"

    def _cancelled(self) -> bool:
        with self._lock:
            return self._cancel is not None

    def _wait(self, seconds: float) -> tuple[bool, str]:
        end = self.clock.now() + seconds
        while self.clock.now() < end:
            if self._cancelled():
                return False, "stopped"
            self.clock.sleep(min(POLL_S, max(0.0, end - self.clock.now())))
        return True, f"waited {seconds:g} s"

    def _wait_topic(self, step: WaitTopic) -> tuple[bool, str]:
        if self.topics is None:
            return False, "no topic access"
        met = threading.Event()
        seen: dict[str, Any] = {"count": 0, "value": None, "error": None}
        want = f"{CONDITION_SIGNS[step.condition]} {describe_value(step.value)}"

        def on_message(msg: Any) -> None:
            try:
                value = field_value(msg, step.field)
                seen["value"], seen["count"] = value, seen["count"] + 1
                if holds(value, step.condition, step.value):
                    met.set()
            except ConditionError as e:
                seen["error"] = str(e)
            except Exception as e:  # noqa: BLE001 - a strange message must not kill the subscriber thread
                seen["error"] = f"cannot read {step.field!r}: {e}"

        try:
            close = self.topics.watch(step.topic, on_message)
        except Exception as e:  # noqa: BLE001
            return False, f"cannot subscribe to {step.topic}: {e}"
        try:
            end = self.clock.now() + step.timeout_s
            while not met.is_set():
                if self._cancelled():
                    return False, "stopped"
                if seen["error"]:
                    return False, f"{step.topic}: {seen['error']}"
                if self.clock.now() >= end:
                    if not seen["count"]:
                        return False, f"no message on {step.topic} within {step.timeout_s:g} s"
                    return False, (f"{step.topic} {step.field} was {describe_value(seen['value'])}, not {want}, "
                                   f"for {step.timeout_s:g} s")
                self.clock.sleep(POLL_S)
            return True, f"{step.topic} {step.field} {want}"
        finally:
            try:
                close()
            except Exception:  # noqa: BLE001 - unsubscribing is best effort
                pass
