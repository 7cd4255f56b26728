"""The UI's side of the process (the client node's logic, no ROS): what Start, Step, Stop, Pause, Resume and dry run
do before anything goes to the action server, the published state built from the server's feedback and results,
the part-cycle counter, "at the start configuration", and the log history.

- One run at a time: Start and Step are refused while a run is active (or while the server is not there, the cell
  is in alarm, or the section is unusable), each with a message the page shows as is.
- The cycle counter: a run starts at the cycle after the last completed one (pose tables pick their entry by it);
  an interrupted cycle is not counted, so the next Start repeats it. Running the last operation alone (Step)
  completes a cycle too. The counter moves on as each cycle completes (not only at the run's end).
- Across a restart of the nodes: the counter and the last cycle's times are the client's `memory()`; the node saves
  it in a state file whenever it changes (so after every completed cycle) and `restore`s it at start. Without a
  saved memory the counter starts at 1.
- Cycle times: `cycle_time_s`/`last_cycle_s` are active time (paused time excluded), `cycle_elapsed_s`/
  `last_cycle_elapsed_s` include the pauses (the executor's Progress carries the paused time).
"""
from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Optional, Sequence

from ..said import say
from ..state_file import finite_number
from .config import ProcessConfig
from .executor import ACTIVE_STATES, ERROR, IDLE, PAUSED, RUNNING, STOPPING, Progress, RunRequest, RunResult

MAX_CYCLE = 2 ** 32 - 1     # ProcessState.cycle is a uint32

LOG_SIZE = 200


@dataclass(frozen=True)
class LogLine:
    stamp: float
    level: str      # info, warning, error
    text: str


class LogBook:
    """The last LOG_SIZE lines, newest last."""

    def __init__(self, size: int = LOG_SIZE) -> None:
        self.lines: deque[LogLine] = deque(maxlen=size)
        self.added = 0      # lines ever added: the node republishes when this changes

    def add(self, level: str, text: str, stamp: float) -> None:
        self.lines.append(LogLine(stamp, level if level in ("info", "warning", "error") else "info", text))
        self.added += 1

    def entries(self) -> list[LogLine]:
        return list(self.lines)


@dataclass
class StateView:
    """The fields of cell_msgs/ProcessState (without the header)."""
    state: str
    ready: bool
    operations: list[str]
    current: int
    step: str
    step_index: int
    step_count: int
    dry_run: bool
    run_mode: str
    cycle: int
    cycles_target: int
    cycles_done: int
    cycle_time_s: float            # active time of the current cycle (paused time excluded)
    cycle_elapsed_s: float         # the same, paused time included
    last_cycle_s: float
    last_cycle_elapsed_s: float
    at_start: bool
    start_configuration: str
    message: str


class ProcessClient:
    def __init__(self, config: Optional[ProcessConfig], config_error: str = "",
                 clock: Callable[[], float] = time.time, alarm_mode: str = "alarm") -> None:
        self.config = config
        self.config_error = config_error
        self.clock = clock
        self.alarm_mode = alarm_mode
        self.log = LogBook()
        self.ready = False
        self.mode: Optional[str] = None
        self.joints: dict[str, list[float]] = {}     # group -> its arm's joint positions (RobotState)
        self.dry_run = False
        self.next_cycle = 1
        self.run: Optional[RunRequest] = None        # the goal sent and not ended yet
        self.state = IDLE
        self.current = -1
        self.step = ""
        self.step_index = -1
        self.step_count = 0
        self.run_mode = ""
        self.cycle = 1
        self.cycles_target = 0
        self.cycles_done = 0
        self.cycle_start = 0.0
        self.cycle_paused_s = 0.0
        self.paused_since = 0.0
        self.last_cycle_s = 0.0
        self.last_cycle_elapsed_s = 0.0
        self.message = config_error or "ready"
        if config_error:
            self.state = ERROR

    # ------------------------------------------------------------------------------------------- inputs
    @property
    def operations(self) -> list[str]:
        return self.config.names if self.config else []

    @property
    def active(self) -> bool:
        return self.run is not None

    def note(self, level: str, text: str, stamp: Optional[float] = None) -> None:
        self.log.add(level, text, self.clock() if stamp is None else stamp)

    def on_mode(self, mode: str) -> None:
        self.mode = mode

    def on_joints(self, positions: Sequence[float], group: Optional[str] = None) -> None:
        """The joint positions of a group's arm (RobotState.joint_positions of /cell/manual/<group>/state);
        group None: process.group."""
        if group is None:
            group = self.config.group if self.config else ""
        self.joints[group] = list(positions)

    def at_start(self) -> bool:
        """Every group of start_configuration stands at its configuration (each of its joints within the
        tolerance). True when the section names none (nothing to confirm); False while a group's joints are
        unknown."""
        cfg = self.config
        if cfg is None or not cfg.start_targets:
            return True
        for t in cfg.start_targets:
            q = self.joints.get(t.group)
            if q is None or not t.indices or max(t.indices) >= len(q):
                return False
            if not all(abs(q[i] - v) <= cfg.start_tolerance for i, v in zip(t.indices, t.joints)):
                return False
        return True

    # ------------------------------------------------------------------------------------------- commands
    def _refusal(self) -> Optional[str]:
        if self.config is None:
            return say("process.reason_config", "the process cannot run: {error}", error=self.config_error)
        if self.active:
            return (say("process.reason_paused", "the process is paused: resume or stop it") if self.state == PAUSED
                    else say("process.reason_running", "the process is already running: stop it first"))
        if self.mode == self.alarm_mode:
            return say("process.reason_alarm_mode", "the cell is in alarm: reset it first")
        if not self.ready:
            return say("process.reason_no_server",
                       "the process server is not running (its action server does not answer)")
        return None

    def start(self, cycles: int) -> tuple[Optional[RunRequest], str]:
        """Start: the request to send, or None and why not."""
        why = self._refusal()
        if why is not None:
            self.note("warning", say("process.start_refused", "Start refused: {reason}", reason=why))
            return None, why
        return self._begin(RunRequest(-1, int(cycles), self.dry_run, self.next_cycle), "cycle")

    def step_request(self, index: int) -> tuple[Optional[RunRequest], str]:
        why = self._refusal()
        if why is None and not 0 <= index < len(self.operations):
            names = ", ".join(f"{i} {n}" for i, n in enumerate(self.operations))
            why = f"no operation {index} (the process has {len(self.operations)}: {names})"
        if why is not None:
            self.note("warning", say("process.step_refused", "Step refused: {reason}", reason=why))
            return None, why
        return self._begin(RunRequest(index, 1, self.dry_run, self.next_cycle), "step")

    def _begin(self, req: RunRequest, mode: str) -> tuple[RunRequest, str]:
        self.run = req
        self.run_mode = mode
        self.state = RUNNING
        self.current, self.step, self.step_index, self.step_count = -1, "", -1, 0
        self.cycle, self.cycles_target, self.cycles_done = req.first_cycle, req.cycles, 0
        self.cycle_start = self.clock()
        self.cycle_paused_s = self.paused_since = 0.0
        self.message = "starting"
        return req, "starting"

    def set_dry_run(self, on: bool) -> tuple[bool, str]:
        if self.active:
            why = say("process.reason_running_dry", "the process is running: change the dry run once it is stopped")
            self.note("warning", say("process.dry_change_refused", "Dry run change refused: {reason}", reason=why))
            return False, why
        if on == self.dry_run:
            return True, f"dry run is already {'on' if on else 'off'}"
        self.dry_run = on
        text = ("dry run on: the process walks its steps without moving the robot" if on
                else "dry run off: the process moves the robot")
        self.note("info", say(f"process.dry_{'on' if on else 'off'}", text[:1].upper() + text[1:]))
        return True, text

    def stop_request(self) -> tuple[bool, str]:
        """Stop: True when a goal must be canceled; else the answer for the caller."""
        if not self.active:
            return False, "the process is not running"
        self.state = STOPPING
        return True, "stopping"

    # ------------------------------------------------------------------------------------------- server events
    def on_feedback(self, fb: Progress) -> None:
        if not self.active:
            return  # late feedback of a run that has ended
        if self.state == STOPPING and fb.state != STOPPING:
            pass    # the cancel is on its way: keep showing stopping
        elif fb.state in ACTIVE_STATES:
            self.state = fb.state
        self.current, self.step_index, self.step_count, self.step = fb.operation, fb.step_index, fb.step_count, fb.step
        self.cycle, self.cycles_done = fb.cycle or self.cycle, fb.cycles_done
        if self.run.operation < 0:
            # Each completed cycle moves the counter on at once: a restart mid-run keeps the cycles already done.
            self.next_cycle = max(self.next_cycle, self.run.first_cycle + fb.cycles_done)
        if fb.cycle_start:
            self.cycle_start = fb.cycle_start
        self.cycle_paused_s, self.paused_since = fb.cycle_paused_s, fb.paused_since
        if fb.last_cycle_s:
            self.last_cycle_s = fb.last_cycle_s
            self.last_cycle_elapsed_s = fb.last_cycle_elapsed_s or fb.last_cycle_s
        if fb.message:
            self.message = fb.message

    def on_rejected(self, why: str) -> None:
        """The server refused the goal (it re-checks: another client may run, the mode may have changed); its log
        line comes from the server."""
        if self.run is None:
            return
        self.run = None
        self.state, self.run_mode, self.message = IDLE, "", why

    def on_result(self, result: RunResult) -> None:
        req = self.run
        if req is None:
            return
        self.run = None
        self.cycles_done = result.cycles_done
        if result.last_cycle_s:
            self.last_cycle_s = result.last_cycle_s
            self.last_cycle_elapsed_s = result.last_cycle_elapsed_s or result.last_cycle_s
        if req.operation < 0:
            self.next_cycle = req.first_cycle + result.cycles_done
        elif result.success and req.operation == len(self.operations) - 1:
            self.next_cycle = req.first_cycle + 1   # the last operation run alone completes the cycle
        self.cycle = self.next_cycle
        self.message = result.message or ("stopped" if result.stopped else "")
        self.run_mode = ""
        self.cycle_start = self.cycle_paused_s = self.paused_since = 0.0
        if result.state == ERROR:
            self.state = ERROR
            self.current, self.step_index, self.step = result.operation, result.step_index, result.step
        else:
            self.state = IDLE
            self.current, self.step, self.step_index, self.step_count = -1, "", -1, 0

    def on_lost(self, why: str) -> None:
        """The server went away during a run (its result will never come)."""
        if self.run is None:
            return
        self.on_result(RunResult(False, why, ERROR, False, self.cycles_done, self.last_cycle_s, self.current,
                                 self.step_index, self.step, self.last_cycle_elapsed_s))
        self.note("error", say("process.error", "Error: {reason}", reason=why))

    # ------------------------------------------------------------------------------------------- output
    def view(self) -> StateView:
        cfg = self.config
        active, elapsed = (0.0, 0.0)
        if self.active:
            active, elapsed = Progress(cycle_start=self.cycle_start, cycle_paused_s=self.cycle_paused_s,
                                       paused_since=self.paused_since).cycle_times(self.clock())
        return StateView(
            state=self.state, ready=self.ready, operations=self.operations, current=self.current, step=self.step,
            step_index=self.step_index, step_count=self.step_count, dry_run=self.dry_run, run_mode=self.run_mode,
            cycle=self.cycle, cycles_target=self.cycles_target, cycles_done=self.cycles_done,
            cycle_time_s=active, cycle_elapsed_s=elapsed, last_cycle_s=self.last_cycle_s,
            last_cycle_elapsed_s=self.last_cycle_elapsed_s, at_start=self.at_start(),
            start_configuration=cfg.start_configuration if cfg else "", message=self.message)

    # ------------------------------------------------------------------------------------------- across a restart
    def memory(self) -> dict[str, Any]:
        """What the node saves in its state file: the next cycle's number and the last cycle's times."""
        return {"next_cycle": self.next_cycle, "last_cycle_s": self.last_cycle_s,
                "last_cycle_elapsed_s": self.last_cycle_elapsed_s}

    def restore(self, memory: Mapping[str, Any]) -> Optional[str]:
        """Take back a memory saved before a restart (while idle, at start); returns what is wrong with it (then
        nothing is taken)."""
        why = memory_problem(memory)
        if why is not None:
            return why
        self.next_cycle = self.cycle = int(memory["next_cycle"])
        self.last_cycle_s = float(memory["last_cycle_s"])
        self.last_cycle_elapsed_s = float(memory["last_cycle_elapsed_s"])
        return None


def memory_problem(memory: Mapping[str, Any]) -> Optional[str]:
    """What is wrong with a saved client memory, or None."""
    n = memory.get("next_cycle")
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_CYCLE:
        return f"next_cycle: expected a whole number from 1 to {MAX_CYCLE}, got {n!r}"
    for key in ("last_cycle_s", "last_cycle_elapsed_s"):
        if not finite_number(memory.get(key)):
            return f"{key}: expected a number of seconds (0 or more), got {memory.get(key)!r}"
    if memory["last_cycle_elapsed_s"] < memory["last_cycle_s"]:
        return (f"last_cycle_elapsed_s ({memory['last_cycle_elapsed_s']!r}) is below last_cycle_s "
                f"({memory['last_cycle_s']!r}): the time with pauses cannot be shorter")
    return None
