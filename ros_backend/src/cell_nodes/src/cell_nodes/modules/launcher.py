"""Starting and stopping a module's launch files: the launcher abstraction and its roslaunch implementation.

RoslaunchLauncher keeps one `roslaunch.parent.ROSLaunchParent` per launched module (the roslaunch Python API; it
works from the manager's worker threads). Every node's stdout and stderr go to its own log files in the ROS log
directory (`$ROS_LOG_DIR/<run_id>/<node>-<n>-stdout.log` / `-stderr.log`), whatever `output=` the launch file says,
so the output service can show the last lines of a module. roslaunch's own messages about the module (a node that
cannot be started, a node that died) are kept as `[launcher]` lines.
"""
from __future__ import annotations

import collections
import os
import threading
import time
from typing import Any, Optional, Protocol, Sequence

from .output import Line, Stream, stream_lines

LaunchFiles = Sequence[tuple[str, Sequence[str]]]  # (absolute path, ["arg:=value", ...]) per launch file
MAX_EVENTS = 100


class LaunchError(RuntimeError):
    """A launch failed (the message says why, for the service's answer)."""


class Launcher(Protocol):
    def start(self, name: str, files: LaunchFiles) -> str:
        """Launch a module's files (blocking until roslaunch has started its processes); returns a short message.
        Raises LaunchError when nothing or not everything could be started (what did start keeps running)."""

    def stop(self, name: str) -> bool:
        """Shut down what this launcher started for the module (blocking until its processes are gone). False when
        it holds nothing for it."""

    def running(self, name: str) -> bool:
        """Whether this launcher holds a launch of the module."""

    def output(self, name: str, lines: int) -> Optional[list[list[Line]]]:
        """The last lines of each stream of the module's latest launch (log files, launcher messages), or None
        when this launcher never launched it."""

    def shutdown(self) -> None:
        """Stop every launch (the node is going down)."""


def _node_name(process_name: str) -> str:
    """roslaunch's process name `vision-1` (`ns/vision-2`) -> the node's name `vision` (`ns/vision`)."""
    base, _, counter = process_name.rpartition("-")
    return base if base and counter.isdigit() else process_name


class _Record:
    """What the output service shows for one module: the log files of its latest launch and launcher messages."""

    def __init__(self) -> None:
        self.streams: list[Stream] = []
        self.events: collections.deque[Line] = collections.deque(maxlen=MAX_EVENTS)
        self.processes: set[str] = set()

    def event(self, text: str) -> None:
        for line in str(text).strip().splitlines() or [""]:
            if line.strip():
                self.events.append(Line(time.time(), f"[launcher] {line.rstrip()}"))


class RoslaunchLauncher:
    def __init__(self, run_id: str, sigint_timeout: float = 2.0, sigterm_timeout: float = 1.0) -> None:
        import roslaunch.core
        self.run_id = run_id
        self.sigint_timeout = sigint_timeout
        self.sigterm_timeout = sigterm_timeout
        self._lock = threading.Lock()
        self._start_lock = threading.Lock()   # one roslaunch start at a time: its messages go to that module
        self._starting: Optional[_Record] = None
        self._parents: dict[str, Any] = {}
        self._records: dict[str, _Record] = {}
        # Child mode makes roslaunch send each node's stderr to `<node>-stderr.log` too (only stdout otherwise);
        # in this process it changes nothing else (roslaunch.nodeprocess is its only reader).
        roslaunch.core.set_child_mode(True)
        roslaunch.core.add_printerrlog_handler(self._roslaunch_message)

    # roslaunch prints problems (a node type not found, a process that died) through printerrlog
    def _roslaunch_message(self, msg: str) -> None:
        """A message naming one of our processes goes to its module; any other during a start to that module."""
        with self._lock:
            record = next((r for r in self._records.values() if any(f"[{p}]" in msg for p in r.processes)),
                          None) or self._starting
        if record is not None:
            record.event(msg)

    def start(self, name: str, files: LaunchFiles) -> str:
        import roslaunch.parent
        import roslaunch.pmon
        from rosgraph.names import ns_join

        with self._lock:
            if name in self._parents:
                raise LaunchError(f"{name} is already launched: stop it first")
            record = self._records[name] = _Record()

        class Listener(roslaunch.pmon.ProcessListener):
            def process_died(self, process_name: str, exit_code: Optional[int]) -> None:
                if not exit_code:  # roslaunch itself reports the others ("process has died [pid ..., exit code -9")
                    record.event(f"{process_name} ended (exit code {exit_code})")

        parent = roslaunch.parent.ROSLaunchParent(
            self.run_id, [(path, list(args)) for path, args in files], is_core=False, process_listeners=[Listener()],
            force_log=True, show_summary=False, sigint_timeout=self.sigint_timeout,
            sigterm_timeout=self.sigterm_timeout)
        with self._start_lock:
            self._starting = record
            try:
                parent.start(auto_terminate=False)
            except BaseException as e:
                record.event(f"launch failed: {e}")
                try:
                    _shut_down(parent)
                except Exception:
                    pass
                raise LaunchError(f"launch failed: {_first_line(e)}") from e
            finally:
                self._starting = None
        with parent.pm.plock:
            procs = list(parent.pm.procs)
        expected = [ns_join(n.namespace, n.name).lstrip("/") for n in parent.config.nodes]
        started = [_node_name(p.name) for p in procs]
        streams: list[Stream] = []
        for p in procs:
            log_dir = getattr(p, "log_dir", None)
            if log_dir:
                base = os.path.join(log_dir, p.name.replace("/", "-"))
                streams.append(Stream(f"[{_node_name(p.name)}]", base + "-stdout.log"))
                streams.append(Stream(f"[{_node_name(p.name)} stderr]", base + "-stderr.log"))
        with self._lock:
            record.streams = streams
            record.processes = {p.name for p in procs}
            self._parents[name] = parent
        missing = [n for n in expected if n not in started]
        record.event(f"started {', '.join(started) or 'nothing'}")
        if missing:
            raise LaunchError(f"could not start {', '.join('/' + n for n in missing)} (see the output)")
        return f"launched {name}: started {', '.join('/' + n for n in started)}"

    def stop(self, name: str) -> bool:
        with self._lock:
            parent = self._parents.pop(name, None)
            record = self._records.get(name)
        if parent is None:
            return False
        _shut_down(parent)
        if record is not None:
            record.event("stopped")
        return True

    def running(self, name: str) -> bool:
        with self._lock:
            return name in self._parents

    def output(self, name: str, lines: int) -> Optional[list[list[Line]]]:
        with self._lock:
            record = self._records.get(name)
            if record is None:
                return None
            streams, events = list(record.streams), list(record.events)
        return [stream_lines(s, lines) for s in streams] + [events[-lines:]]

    def shutdown(self) -> None:
        with self._lock:
            names = list(self._parents)
        threads = [threading.Thread(target=self.stop, args=(n,), daemon=True) for n in names]
        for t in threads:
            t.start()
        deadline = time.monotonic() + self.sigint_timeout + self.sigterm_timeout + 1.0
        for t in threads:
            t.join(max(0.0, deadline - time.monotonic()))


def _shut_down(parent: Any, wait_s: float = 2.0) -> None:
    """`parent.shutdown()`, and the end of its XML-RPC server's thread. rosgraph's XmlRpcNode.shutdown closes the
    server's socket but never ends the socketserver loop serving it, which then polls the closed socket (POLLNVAL)
    at full speed for good: one spinning thread in this node per module ever stopped (half a core after two stops)."""
    server = getattr(getattr(parent, "server", None), "server", None)  # the socketserver, gone after shutdown
    parent.shutdown()
    if server is not None:
        # socketserver's shutdown() waits for the loop to end; it never ends if the loop never started (a start that
        # failed early), hence its own thread and a bounded wait.
        ender = threading.Thread(target=server.shutdown, name="roslaunch-server-end", daemon=True)
        ender.start()
        ender.join(wait_s)


def _first_line(e: BaseException) -> str:
    text = str(e).strip() or type(e).__name__
    return text.splitlines()[0][:300]

