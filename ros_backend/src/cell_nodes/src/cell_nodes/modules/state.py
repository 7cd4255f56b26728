"""The state of one module, from which of its nodes are alive (checked every second) and what was asked of it.

- active: every node of the module is alive
- inactive: none is alive
- incomplete: some are alive, some are not; or a launch/stop did not settle within the module's timeout
- transitioning: a launch or a stop was accepted and has not settled yet (all up; or all gone and the launcher's
  launch of it shut down)

Nodes started or killed from a terminal count like any other: the state follows the liveness of the nodes, not
who started them. A timed-out transition stays incomplete until the liveness of its nodes changes (or another
command is accepted); then the state follows the liveness again. A module without node names is active while the
launcher holds a launch of it, inactive otherwise.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Callable, Collection, Optional

from .config import ModuleSpec

ACTIVE = "active"
INACTIVE = "inactive"
TRANSITIONING = "transitioning"
INCOMPLETE = "incomplete"
STATES = (ACTIVE, INACTIVE, TRANSITIONING, INCOMPLETE)


class Decision(enum.Enum):
    REFUSE = "refuse"   # answer success: false
    NOOP = "noop"       # nothing to do (already active / inactive / launching / stopping): success: true
    DO = "do"           # accepted: the state goes transitioning, the worker does it


@dataclass(frozen=True)
class Status:
    name: str
    state: str
    nodes: tuple[str, ...]
    alive: tuple[bool, ...]        # alive[i] for nodes[i]
    launchable: bool
    launched: bool                 # the launcher holds a launch of this module
    target: str                    # while transitioning: active (launching) or inactive (stopping); else ""
    message: str
    since: float                   # clock time the module entered this state


def _names(nodes: Collection[str]) -> str:
    return ", ".join(nodes)


class ModuleMachine:
    """Not thread-safe: the manager calls it under its lock."""

    def __init__(self, spec: ModuleSpec, clock: Callable[[], float]) -> None:
        self.spec = spec
        self._clock = clock
        self._alive: frozenset[str] = frozenset()
        self._running = False
        self._goal: Optional[str] = None         # ACTIVE (launching) or INACTIVE (stopping)
        self._deadline = 0.0
        self._stuck: Optional[frozenset[str]] = None  # alive set when a transition timed out
        self._note: Optional[tuple[str, str]] = None  # (state, message): shown while the state stays
        self._state = INACTIVE
        self._message = ""
        self._since = clock()
        self._evaluate()

    # ------------------------------------------------------------------ inputs
    def observe(self, alive: Collection[str], running: bool) -> bool:
        """A liveness check: the names of the module's nodes that are alive, whether the launcher holds a launch
        of it. Returns whether the status changed."""
        before = self.status()
        self._alive = frozenset(n for n in alive if n in self.spec.nodes)
        self._running = bool(running)
        if self._stuck is not None and self._alive != self._stuck:
            self._stuck = None  # the liveness moved on after a timed-out transition: follow it again
            self._note = None
        self._evaluate()
        return self.status() != before

    def refresh(self) -> bool:
        """Re-evaluate at the current time (the transition timeout) without a new observation."""
        before = self.status()
        self._evaluate()
        return self.status() != before

    def decide_launch(self) -> tuple[Decision, str]:
        name = self.spec.name
        if not self.spec.launchable:
            return Decision.REFUSE, f"{name} cannot be launched: it has no launch files (monitored only)"
        if self._goal == INACTIVE:
            return Decision.REFUSE, f"{name} is stopping: launch it once it is inactive"
        if self._goal == ACTIVE:
            return Decision.NOOP, f"{name} is already launching"
        if self._state == ACTIVE:
            return Decision.NOOP, f"{name} is already active"
        return Decision.DO, f"launching {name}"

    def decide_stop(self) -> tuple[Decision, str]:
        name = self.spec.name
        if not self.spec.launchable:
            return Decision.REFUSE, (f"{name} cannot be stopped: it has no launch files (monitored only; it is "
                                     f"started outside the modules node)")
        if self._goal == INACTIVE:
            return Decision.NOOP, f"{name} is already stopping"
        if self._goal is None and self._state == INACTIVE and not self._running:
            return Decision.NOOP, f"{name} is already inactive"
        return Decision.DO, f"stopping {name}"

    def begin(self, target: str) -> None:
        """A launch (target active) or a stop (target inactive) was accepted."""
        if target not in (ACTIVE, INACTIVE):
            raise ValueError(f"target must be {ACTIVE} or {INACTIVE}, not {target!r}")
        self._goal = target
        self._deadline = self._clock() + self.spec.timeout_s
        self._stuck = None
        self._note = None
        self._evaluate()

    def fail(self, message: str) -> None:
        """The launcher could not do it: the transition ends, the state follows the liveness, with `message`."""
        self._goal = None
        self._stuck = None
        self._evaluate()
        self._note = (self._state, message)
        self._message = message

    # ------------------------------------------------------------------ output
    @property
    def state(self) -> str:
        return self._state

    @property
    def goal(self) -> Optional[str]:
        return self._goal

    def status(self) -> Status:
        nodes = self.spec.nodes
        return Status(name=self.spec.name, state=self._state, nodes=nodes,
                      alive=tuple(n in self._alive for n in nodes), launchable=self.spec.launchable,
                      launched=self._running, target=self._goal or "", message=self._message, since=self._since)

    # ------------------------------------------------------------------ the rules
    def _natural(self) -> str:
        nodes = self.spec.nodes
        if not nodes:
            return ACTIVE if self._running else INACTIVE
        up = len(self._alive)
        return ACTIVE if up == len(nodes) else INACTIVE if up == 0 else INCOMPLETE

    def _evaluate(self) -> None:
        natural = self._natural()
        nodes = self.spec.nodes
        missing = [n for n in nodes if n not in self._alive]
        running = [n for n in nodes if n in self._alive]
        if self._goal is not None:
            # a launch settles when every node answers; a stop when none does and the launcher let go of it
            if natural == self._goal and (self._goal == ACTIVE or not self._running):
                self._goal = None
            elif self._clock() >= self._deadline:
                what = "launch" if self._goal == ACTIVE else "stop"
                rest = (f"not running: {_names(missing)}" if self._goal == ACTIVE else
                        f"still running: {_names(running)}" if running else "still held by the launcher")
                self._goal = None
                self._stuck = self._alive
                self._set(INCOMPLETE, f"{what} did not complete within {self.spec.timeout_s:g} s; {rest}")
                self._note = (INCOMPLETE, self._message)
                return
            else:
                if self._goal == ACTIVE:
                    msg = f"launching: {len(running)} of {len(nodes)} nodes up" if nodes else "launching"
                else:
                    msg = f"stopping: {len(running)} of {len(nodes)} nodes still running" if nodes else "stopping"
                self._set(TRANSITIONING, msg)
                return
        if self._stuck is not None:
            self._set(INCOMPLETE, self._message)
            return
        if natural == ACTIVE:
            msg = f"all {len(nodes)} nodes running" if len(nodes) > 1 else "its node is running" if nodes else "running"
        elif natural == INACTIVE:
            msg = "not running"
        else:
            msg = f"not running: {_names(missing)}"
        self._set(natural, msg)

    def _set(self, state: str, message: str) -> None:
        if state != self._state:
            self._state = state
            self._since = self._clock()
        if self._note is not None:
            if self._note[0] == state:
                message = self._note[1]
            else:
                self._note = None
        self._message = message
