"""The modules of the cell file, what the services ask of them, and the one-second liveness check.

Launch and stop run in one worker thread per module (a module's commands run in order; modules run side by
side), so they never hold up the other services or the state. A launch answers once roslaunch has started the
module's processes (at most `launch_wait_s`, then "still starting"); a stop answers at once. In both cases the
state goes transitioning at once and settles from the liveness checks.

Only names from the cell file are accepted; the launch files come from the cell file too (package-relative
references resolved inside their package), never from a request.
"""
from __future__ import annotations

import logging
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Callable, Optional, Sequence

from .config import ConfigError, ModuleSpec
from .graph import Graph, GraphError
from .launcher import Launcher, LaunchError
from .output import RosoutBuffer, clamp_lines, merge
from .state import ACTIVE, INACTIVE, Decision, ModuleMachine, Status

log = logging.getLogger("cell_nodes.modules")


class ModulesManager:
    def __init__(self, specs: Sequence[ModuleSpec], launcher: Launcher, graph: Graph,
                 resolve: Callable[[str], str], launch_args: Sequence[str] = (),
                 rosout: Optional[RosoutBuffer] = None, clock: Callable[[], float] = time.monotonic,
                 launch_wait_s: float = 5.0, on_change: Optional[Callable[[], None]] = None) -> None:
        self.launcher = launcher
        self.graph = graph
        self.resolve = resolve
        self.launch_args = list(launch_args)
        self.rosout = rosout
        self.launch_wait_s = launch_wait_s
        self.on_change = on_change or (lambda: None)
        self._lock = threading.RLock()
        self._machines = {s.name: ModuleMachine(s, clock) for s in specs}
        self._workers = {s.name: ThreadPoolExecutor(max_workers=1, thread_name_prefix=f"module-{i}")
                         for i, s in enumerate(specs) if s.launchable}
        self._nodes = list(dict.fromkeys(n for s in specs for n in s.nodes))
        self.master_ok = True

    @property
    def names(self) -> list[str]:
        return list(self._machines)

    def _unknown(self, name: str) -> str:
        return f"unknown module {name!r} (the cell has: {', '.join(self._machines) or 'no modules'})"

    def statuses(self) -> list[Status]:
        with self._lock:
            return [m.status() for m in self._machines.values()]

    # ------------------------------------------------------------------ the one-second check
    def poll(self) -> list[Status]:
        """Check which nodes are alive and update every module; returns the statuses."""
        try:
            alive: Optional[set[str]] = self.graph.alive(self._nodes) if self._nodes else set()
            if not self.master_ok:
                log.info("the ROS master answers again")
            self.master_ok = True
        except GraphError as e:
            if self.master_ok:
                log.warning("%s", e)
            self.master_ok = False
            alive = None
        with self._lock:
            for name, m in self._machines.items():
                if alive is None:
                    m.refresh()
                else:
                    m.observe(alive, self.launcher.running(name))
            return [m.status() for m in self._machines.values()]

    # ------------------------------------------------------------------ services
    def launch(self, name: str) -> tuple[bool, str]:
        m = self._machines.get(name)
        if m is None:
            return False, self._unknown(name)
        with self._lock:
            decision, message = m.decide_launch()
            if decision is not Decision.DO:
                return decision is Decision.NOOP, message
            m.begin(ACTIVE)
        self.on_change()
        future: Future[str] = self._workers[name].submit(self._do_launch, m)
        try:
            return True, future.result(timeout=self.launch_wait_s)
        except LaunchError as e:
            return False, str(e)
        except FutureTimeout:
            return True, f"launching {name}: roslaunch is still starting it"

    def stop(self, name: str) -> tuple[bool, str]:
        m = self._machines.get(name)
        if m is None:
            return False, self._unknown(name)
        with self._lock:
            decision, message = m.decide_stop()
            if decision is not Decision.DO:
                return decision is Decision.NOOP, message
            m.begin(INACTIVE)
        self.on_change()
        self._workers[name].submit(self._do_stop, m)
        return True, message

    def output(self, name: str, lines: int) -> tuple[bool, str, list[str]]:
        m = self._machines.get(name)
        if m is None:
            return False, self._unknown(name), []
        n = clamp_lines(lines)
        groups = self.launcher.output(name, n)
        if groups is not None:
            source = "its nodes' output since its latest launch"
        else:
            groups = self.rosout.lines(m.spec.nodes) if self.rosout is not None else []
            source = "its nodes' /rosout messages (not launched by the modules node)"
        out = merge(groups, n)
        return True, f"{len(out)} lines of {name}: {source}", out

    # ------------------------------------------------------------------ the workers
    def _fail(self, m: ModuleMachine, message: str) -> None:
        with self._lock:
            m.fail(message)
        self.on_change()

    def _do_launch(self, m: ModuleMachine) -> str:
        name = m.spec.name
        try:
            if self.launcher.stop(name):
                log.info("%s: replaced its previous launch", name)
            files = [(self.resolve(ref), list(self.launch_args)) for ref in m.spec.launch]
            message = self.launcher.start(name, files)
        except ConfigError as e:
            self._fail(m, f"launch failed: {e}")
            raise LaunchError(f"launch failed: {e}") from e
        except LaunchError as e:
            self._fail(m, str(e))
            raise
        except Exception as e:  # roslaunch raises many kinds; the state must not stay transitioning
            log.exception("%s: launch failed", name)
            self._fail(m, f"launch failed: {e}")
            raise LaunchError(f"launch failed: {e}") from e
        log.info("%s", message)
        return message

    def _do_stop(self, m: ModuleMachine) -> None:
        name = m.spec.name
        try:
            ours = self.launcher.stop(name)
            others = self.graph.alive(m.spec.nodes) if m.spec.nodes else set()
            killed = self.graph.kill(others) if others else []
            log.info("%s: stopped%s%s", name, " its launch" if ours else "",
                     f"; asked {', '.join(killed)} to shut down" if killed else "")
        except Exception as e:
            log.exception("%s: stop failed", name)
            self._fail(m, f"stop failed: {e}")

    def shutdown(self) -> None:
        for w in self._workers.values():
            w.shutdown(wait=False, cancel_futures=True)
        self.launcher.shutdown()
