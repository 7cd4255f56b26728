"""What the node tests (test_*_node.py) share: `rosrun cell_nodes <node>` in a session of its own with its output in
a log file, waiting until the nodes' services answer (a node that ends meanwhile fails at once, with its log),
stopping them (SIGINT, then SIGKILL to the session), their logs checked; this test process as a ROS client node; a
simulated controller started and ready.

The roscore is the repository conftest's `roscore` fixture (a free port, one per session). While a node runs, a test
that fails gets the end of its log in its report (the repository's conftest.py asks `running_logs()`).
A module of its own name, not a conftest.py: the test modules' `from conftest import wait_for` means the
repository's conftest.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, List, Mapping, Optional

from cell_nodes import wiring
from conftest import wait_for

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"

LOG_TAIL = 3000        # characters of a log shown with a failure
STOP_TIMEOUT_S = 10.0  # after SIGINT, then SIGKILL to the node's session

_running: list["Node"] = []


_peer: List[wiring.Wiring] = []


def peer(name: str = "node_tests") -> wiring.Wiring:
    """This test process as a ROS node of the session's generation, through the nodes' own wiring (one per
    process: another module of the session may have made it, under its name)."""
    if not _peer:
        _peer.append(wiring.connect(name, anonymous=True, disable_signals=True))
    return _peer[0]


def service_up(name: str) -> bool:
    if wiring.ROS_VERSION == 1:  # no node needed (the master answers), as before any client_node
        import rospy
        try:
            rospy.wait_for_service(name, timeout=0.2)
            return True
        except rospy.ROSException:
            return False
    return name in {n for n, _ in peer().node.get_service_names_and_types()}  # type: ignore[attr-defined]


def client_node(name: str) -> None:
    """Make this test process a ROS node (one per process: another module of the session may have made it)."""
    peer(name)


def ros2_args(args: List[str]) -> List[str]:
    """A ROS 1 node's command line (`_param:=value`, `__name:=n`, `from:=to`) in ROS 2 form (`--ros-args -p ...`)."""
    out: List[str] = []
    for arg in args:
        key, sep, value = arg.partition(":=")
        if not sep:
            out.append(arg)
        elif key == "__name":
            out += ["-r", f"__node:={value}"]
        elif key.startswith("_") and not key.startswith("__"):
            out += ["-p", f"{key[1:]}:={value}"]
        else:
            out += ["-r", arg]
    plain = [a for a in out if a not in ("-r", "-p") and ":=" not in a]
    ros = [a for a in out if a not in plain]
    return plain + (["--ros-args", *ros] if ros else [])


def start_sim(host: str, *args: str, master: Optional[str] = None) -> Any:
    """`python -m sim --host <host> <args>` (no ROS master unless `master`), ready: its controller ports answer."""
    from sim.tests.conftest import NO_MASTER, SimProcess, sim_env
    sim = SimProcess(host, list(args), sim_env(master or NO_MASTER))
    try:
        sim.wait_ready()
    except BaseException:
        sim.stop()
        raise
    return sim


def running_logs() -> list[tuple[str, str]]:
    """(label, the end of its log) of each node running now."""
    return [(node.label, node.tail()) for node in _running]


class Node:
    """`rosrun cell_nodes <script> <args>` in a session of its own; its stdout and stderr in a log file."""

    def __init__(self, script: str, *args: str, label: str = "", env: Optional[Mapping[str, str]] = None) -> None:
        self.label = label or script
        fd, path = tempfile.mkstemp(prefix=f"{self.label}-", suffix=".log", dir=os.environ.get("ROS_LOG_DIR"))
        self.log_path = Path(path)
        try:
            command = ["rosrun", "cell_nodes", script, *args] if wiring.ROS_VERSION == 1 else \
                [sys.executable, str(SCRIPTS / script), *ros2_args(list(args))]
            self.proc = subprocess.Popen(command, stdout=fd, stderr=subprocess.STDOUT,
                                         env=None if env is None else dict(env), start_new_session=True)
        finally:
            os.close(fd)
        self.took: Optional[float] = None     # seconds from SIGINT to its end, once stopped
        self._output: Optional[str] = None    # the whole log, once stopped (the file is removed then)
        _running.append(self)

    def alive(self) -> bool:
        """True while it runs; a node that ended fails the test at once, with its log."""
        if self.proc.poll() is not None:
            raise AssertionError(f"{self.label} exited ({self.proc.returncode}):\n{self.tail()}")
        return True

    def output(self) -> str:
        return self._output if self._output is not None else self.log_path.read_text(errors="replace")

    def tail(self) -> str:
        return self.output()[-LOG_TAIL:]

    def interrupt(self) -> None:
        """SIGINT; a node that already ended took no time to stop."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        elif self.took is None:
            self.took = 0.0

    def finish(self, since: float) -> float:
        """Wait for its end, SIGKILL to its session STOP_TIMEOUT_S after `since` (the SIGINT); keep the output, remove
        the log file. Returns the seconds from `since` to its end."""
        try:
            self.proc.wait(max(0.0, since + STOP_TIMEOUT_S - time.monotonic()))
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(5)
        if self.took is None:
            self.took = time.monotonic() - since
        self._close()
        return self.took

    def stop(self) -> float:
        """SIGINT, its end awaited (see finish)."""
        t0 = time.monotonic()
        self.interrupt()
        return self.finish(t0)

    def kill(self) -> None:
        """SIGKILL to its session, as a crash or a power cut: nothing the node would do on shutdown happens."""
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
        self.proc.wait(5)
        self._close()

    def _close(self) -> None:
        """Keep the output, remove the log file."""
        if self._output is None:
            self._output = self.output()
            self.log_path.unlink(missing_ok=True)
        if self in _running:
            _running.remove(self)

    def check(self, within: Optional[float] = None) -> None:
        """Its log holds no traceback; stopped within `within` s of the SIGINT (when given)."""
        assert "Traceback" not in self.output(), f"{self.label} logged a traceback:\n{self.tail()}"
        if within is not None:
            assert self.took is not None and self.took < within, \
                f"{self.label} took {self.took:.1f} s to stop (at most {within} s):\n{self.tail()}"


class Nodes:
    """The nodes of a test module: started one by one, ready when their services answer, stopped together.

        nodes = Nodes()
        nodes.run("alarms", "alarms_node", f"_cell_config:={path}", "__name:=alarms_test")
        try:
            nodes.wait_ready("/cell/alarms/reset")
            yield ...
        finally:
            nodes.stop()           # never raises: whatever else the fixture stops comes next
            nodes.check(within=5)  # no traceback in any log, each stopped within 5 s
    """

    def __init__(self) -> None:
        self.nodes: list[Node] = []

    def run(self, label: str, script: str, *args: str, env: Optional[Mapping[str, str]] = None) -> Node:
        node = Node(script, *args, label=label, env=env)
        self.nodes.append(node)
        return node

    def alive(self) -> bool:
        """True while every node runs; a node that ended fails the test at once, with its log."""
        return all(node.alive() for node in self.nodes)

    def output(self, label: str) -> str:
        return next(node.output() for node in self.nodes if node.label == label)

    def wait_ready(self, *services: str, timeout: float = 30.0, what: str = "") -> None:
        """Until every node runs and every service answers (the nodes' and any other's)."""
        try:
            wait_for(lambda: self.alive() and all(service_up(s) for s in services), timeout,
                     what=what or ", ".join(services))
        except AssertionError as e:
            if not str(e).startswith("timed out"):
                raise   # a node ended: its log is in the message
            logs = "\n".join(f"--- {node.label}:\n{node.tail()}" for node in self.nodes)
            raise AssertionError(f"{e}\n{logs}") from None

    def stop(self) -> dict[str, float]:
        """SIGINT to every node at once, each end awaited (SIGKILL to its session after STOP_TIMEOUT_S). Returns the
        seconds each took; never fails (see check)."""
        t0 = time.monotonic()
        for node in self.nodes:
            node.interrupt()
        pending = list(self.nodes)
        while pending:   # each end taken when it comes: the nodes stop side by side
            for node in [n for n in pending if n.proc.poll() is not None or time.monotonic() > t0 + STOP_TIMEOUT_S]:
                node.finish(t0)
                pending.remove(node)
            if pending:
                time.sleep(0.01)
        took = {node.label: node.took or 0.0 for node in self.nodes}
        print(f"\nnodes stopped after SIGINT in: {', '.join(f'{k} {v:.2f} s' for k, v in took.items())}")
        return took

    def check(self, within: Optional[float] = None) -> None:
        """After stop: no node logged a traceback; each stopped within `within` s (when given)."""
        for node in self.nodes:
            node.check(within)
