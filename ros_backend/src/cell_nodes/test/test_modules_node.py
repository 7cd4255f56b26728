"""The modules node end to end: roscore + `rosrun cell_nodes modules_node` with the demo cell, used over ROS the way
the BFF relays the page's calls, and watched on /cell/modules/state: the Vision module launched through the
service (transitioning, then active), one of its nodes killed with SIGKILL (incomplete within 3 s), its output,
its stop (inactive); a module started from a terminal and stopped through the service; refused names."""
from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
import xmlrpc.client
from pathlib import Path
from typing import Iterator, Optional

import pytest
import rospy

from conftest import wait_for
from nodes_helpers import Node, Nodes, client_node

CELL = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"
LEFT_RUNNING: list[int] = []  # pids of module nodes left launched: the node must stop them when it stops


class States:
    """Every /cell/modules/state message, as {module name: (state, alive, launched, message)} with its time."""

    def __init__(self) -> None:
        from cell_msgs.msg import ModuleStates
        self.history: list[tuple[float, dict[str, tuple]]] = []
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber("/cell/modules/state", ModuleStates, self._cb, queue_size=100)

    def _cb(self, msg) -> None:
        snap = {m.name: (m.state, tuple(m.alive), m.launched, m.message) for m in msg.modules}
        with self._lock:
            self.history.append((time.monotonic(), snap))

    def now(self, name: str) -> Optional[tuple]:
        with self._lock:
            return self.history[-1][1].get(name) if self.history else None

    def state(self, name: str) -> Optional[str]:
        s = self.now(name)
        return s[0] if s else None

    def since(self, t0: float, name: str) -> list[str]:
        """The states of a module in the messages received after t0, repeats collapsed."""
        with self._lock:
            seq = [snap[name][0] for t, snap in self.history if t >= t0 and name in snap]
        return [s for i, s in enumerate(seq) if i == 0 or s != seq[i - 1]]


def _pid_of(node: str) -> int:
    import rosgraph
    uri = rosgraph.Master("/modules_test_client").lookupNode(node)
    return int(xmlrpc.client.ServerProxy(uri).getPid("/modules_test_client")[2])


def _cpu_seconds(pid: int, window: float) -> float:
    """The CPU time a process used over the next `window` seconds."""
    def total() -> float:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime
    t0 = total()
    time.sleep(window)
    return total() - t0


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:
        return f.read().split(")")[-1].split()[0] != "Z"


@pytest.fixture(scope="module")
def node(roscore: str) -> Iterator[subprocess.Popen]:
    nodes = Nodes()
    modules = nodes.run("modules", "modules_node", f"_cell_config:={CELL}", "__name:=modules_test")
    try:
        client_node("modules_test_client")
        nodes.wait_ready("/cell/modules/output")
        yield modules.proc
    finally:
        nodes.stop()
        nodes.check(within=8)
        left = [p for p in LEFT_RUNNING if _alive(p)]
        for p in left:
            os.kill(p, signal.SIGKILL)
        assert not left, "module nodes outlived the modules node"


def test_launch_kill_output_stop_and_refusals(node) -> None:
    from cell_msgs.srv import ModuleCommand, ModuleOutput

    launch = rospy.ServiceProxy("/cell/modules/launch", ModuleCommand)
    stop = rospy.ServiceProxy("/cell/modules/stop", ModuleCommand)
    output = rospy.ServiceProxy("/cell/modules/output", ModuleOutput)
    states = States()
    wait_for(lambda: states.state("Vision") == "inactive", 10, what="the latched state, Vision inactive")
    assert set(states.history[-1][1]) == {"Simulated cell", "Vision", "Diagnostics"}
    assert states.now("Simulated cell")[:3] == ("inactive", (False,), False)  # no sim in this test

    # --- launch: the call answers once roslaunch started the nodes; transitioning, then active
    t0 = time.monotonic()
    r = launch(name="Vision")
    assert r.success and r.message == "launched Vision: started /vision, /vision_monitor", r.message
    wait_for(lambda: states.state("Vision") == "active", 15, what="Vision active")
    seq = states.since(t0, "Vision")  # (a check may have published "inactive" just before the call's answer)
    assert seq[-2:] == ["transitioning", "active"] and set(seq) <= {"inactive", "transitioning", "active"}, seq
    assert states.now("Vision")[1:3] == ((True, True), True)
    again = launch(name="Vision")
    assert again.success and again.message == "Vision is already active"

    # --- kill -9 one of its nodes: incomplete within 3 s, and the master forgets the dead node
    victim = _pid_of("/vision")
    survivor = _pid_of("/vision_monitor")
    with open(f"/proc/{victim}/cmdline", "rb") as f:
        assert b"vision_node" in f.read()
    t_kill = time.monotonic()
    os.kill(victim, signal.SIGKILL)
    wait_for(lambda: states.state("Vision") == "incomplete", 3, what="Vision incomplete after kill -9")
    print(f"\nincomplete {time.monotonic() - t_kill:.2f} s after kill -9")
    assert states.now("Vision")[1] == (False, True) and states.now("Vision")[3] == "not running: /vision"
    import rosgraph
    with pytest.raises(rosgraph.MasterError):
        rosgraph.Master("/modules_test_client").lookupNode("/vision")

    # --- output: the last lines of its nodes, roslaunch's word on the killed one, bounded
    out = output(name="Vision", lines=50)
    assert out.success and 0 < len(out.lines) <= 50, out
    text = "\n".join(out.lines)
    assert "[vision] [INFO]" in text and "vision: watching /cell/camera/workbench/image/compressed" in text
    assert "[vision_monitor] [INFO]" in text
    assert any(x.startswith("[launcher]") and "exit code -9" in x for x in out.lines), text
    assert len(output(name="Vision", lines=100000).lines) <= 200
    assert len(output(name="Vision", lines=2).lines) == 2

    # --- stop: inactive, its processes gone
    t0 = time.monotonic()
    r = stop(name="Vision")
    assert r.success and r.message == "stopping Vision"
    wait_for(lambda: states.state("Vision") == "inactive", 10, what="Vision inactive after stop")
    assert states.since(t0, "Vision")[-2:] == ["transitioning", "inactive"]
    assert states.now("Vision")[1:3] == ((False, False), False)
    wait_for(lambda: not _alive(survivor), 5, what="vision_monitor's process to end")
    # Nothing of the stopped launch keeps running in the node: roslaunch's XML-RPC server thread spun on its closed
    # socket for good (a whole core's share per stopped module) before launcher._shut_down ended it.
    me = _pid_of("/modules_test")
    wait_for(lambda: _cpu_seconds(me, 1.0) < 0.3, 10, what="the modules node idle after the stop")

    # --- names not in the cell file, monitor-only modules
    for call in (launch, stop):
        bad = call(name="Nope")
        assert not bad.success and bad.message.startswith("unknown module 'Nope' (the cell has: Simulated cell")
    bad = output(name="Nope", lines=5)
    assert not bad.success and not bad.lines
    sim = launch(name="Simulated cell")
    assert not sim.success and "cannot be launched" in sim.message


def test_a_module_started_from_a_terminal_is_seen_and_stopped(node) -> None:
    from cell_msgs.srv import ModuleCommand

    states = States()
    wait_for(lambda: states.state("Diagnostics") == "inactive", 10, what="Diagnostics inactive")
    term = Node("system_monitor_node", label="system_monitor-terminal")
    try:
        wait_for(lambda: states.state("Diagnostics") == "active", 15, what="Diagnostics active (terminal)")
        assert states.now("Diagnostics")[1:3] == ((True,), False)  # alive, not launched by the node
        t0 = time.monotonic()
        r = rospy.ServiceProxy("/cell/modules/stop", ModuleCommand)(name="Diagnostics")
        assert r.success and r.message == "stopping Diagnostics"
        wait_for(lambda: states.state("Diagnostics") == "inactive", 10, what="Diagnostics inactive")
        assert states.since(t0, "Diagnostics")[-2:] == ["transitioning", "inactive"]
        term.proc.wait(10)  # rosnode-kill made the terminal's node shut down

        # launched through the service this time, and left running: the node stops it when it stops (fixture)
        r = rospy.ServiceProxy("/cell/modules/launch", ModuleCommand)(name="Diagnostics")
        assert r.success and r.message == "launched Diagnostics: started /system_monitor", r.message
        wait_for(lambda: states.state("Diagnostics") == "active", 15, what="Diagnostics active (launched)")
        assert states.now("Diagnostics")[1:3] == ((True,), True)
        LEFT_RUNNING.append(_pid_of("/system_monitor"))
    finally:
        term.stop()
