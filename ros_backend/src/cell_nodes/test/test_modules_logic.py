"""Modules, the plain-Python logic (no ROS, no roscore): the cell file section and launch file references, the
per-module state machine with a fake clock and a fake liveness source (every transition of the four states,
nodes started and killed from a terminal, the timeout), the manager with a fake launcher and a fake graph (names
from the cell file only, workers that never block the services), the liveness check against a fake master and
fake nodes over real XML-RPC (dead nodes cleaned, silent ones bounded), the output buffers, the demo computations."""
from __future__ import annotations

import io
import os
import socket
import threading
import time
from pathlib import Path
from typing import Any, Optional
from xmlrpc.server import SimpleXMLRPCServer

import pytest
import yaml

from cell_nodes.modules import demo
from cell_nodes.modules.config import ConfigError, ModuleSpec, parse_modules, resolve_launch_file
from cell_nodes.modules.graph import GraphError, MasterGraph
from cell_nodes.modules.launcher import LaunchError
from cell_nodes.modules.manager import ModulesManager
from cell_nodes.modules.output import (MAX_LINES, Line, RosoutBuffer, Stream, clamp_lines, merge, stream_lines,
                                       tail_file)
from cell_nodes.modules.state import (ACTIVE, INACTIVE, INCOMPLETE, STATES, TRANSITIONING, Decision,
                                      ModuleMachine)
from conftest import wait_for

ROOT = Path(__file__).resolve().parents[4]
DEMO = ROOT / "config" / "demo-cell.yaml"


class FakeClock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t

    def advance(self, s: float) -> None:
        self.t += s


# ---------------------------------------------------------------------------------------------- the cell file
def test_demo_cell_modules_section() -> None:
    specs = parse_modules(yaml.safe_load(DEMO.read_text())["modules"])
    by = {s.name: s for s in specs}
    assert list(by) == ["Simulated cell", "Vision", "Diagnostics"]
    sim = by["Simulated cell"]
    assert not sim.launchable and sim.nodes == ("/sim_cell",)
    vision = by["Vision"]
    assert vision.launchable and vision.nodes == ("/vision", "/vision_monitor") and vision.timeout_s == 10
    assert vision.launch == ("cell_bringup/launch/modules/vision.launch",)
    assert by["Diagnostics"].roles == ("admin", "operator") and by["Diagnostics"].timeout_s == 10.0
    for s in specs:  # every launch file of the demo exists inside its package
        for ref in s.launch:
            assert Path(resolve_launch_file(ref, lambda pkg: str(ROOT / "ros_backend" / "src" / pkg))).is_file()


@pytest.mark.parametrize("entry, field", [
    ({"name": ""}, "modules[0].name"),
    ({"name": "A", "launch": ["/etc/passwd.launch"]}, "modules[0].launch[0]"),
    ({"name": "A", "launch": ["cell_bringup/../../x.launch"]}, "modules[0].launch[0]"),
    ({"name": "A", "launch": ["cell_bringup/launch/x.py"]}, "modules[0].launch[0]"),
    ({"name": "A", "nodes": ["/ok", "bad name"]}, "modules[0].nodes[1]"),
    ({"name": "A", "timeout_s": 0}, "modules[0].timeout_s"),
    ({"name": "A", "timeout_s": True}, "modules[0].timeout_s"),
])
def test_bad_entries_name_the_field(entry: dict, field: str) -> None:
    with pytest.raises(ConfigError, match=field.replace("[", r"\[").replace("]", r"\]")):
        parse_modules([entry])


def test_duplicate_names_and_relative_node_names() -> None:
    with pytest.raises(ConfigError, match=r"modules\[1\].name: duplicate"):
        parse_modules([{"name": "A"}, {"name": "A"}])
    (a,) = parse_modules([{"name": "A", "nodes": ["x", "/x", "/ns/y"]}])
    assert a.nodes == ("/x", "/ns/y") and a.launch == () and a.timeout_s == 10.0
    assert parse_modules(None) == []


def test_launch_references_resolve_only_inside_their_package(tmp_path: Path) -> None:
    pkg = tmp_path / "pkg"
    (pkg / "launch").mkdir(parents=True)
    (pkg / "launch" / "a.launch").write_text("<launch/>")
    (tmp_path / "outside.launch").write_text("<launch/>")
    (pkg / "launch" / "escape.launch").symlink_to(tmp_path / "outside.launch")

    def find(name: str) -> str:
        if name != "pkg":
            raise KeyError(name)
        return str(pkg)

    assert resolve_launch_file("pkg/launch/a.launch", find) == str(pkg / "launch" / "a.launch")
    with pytest.raises(ConfigError, match="outside the package"):
        resolve_launch_file("pkg/launch/escape.launch", find)
    with pytest.raises(ConfigError, match="no such launch file"):
        resolve_launch_file("pkg/launch/b.launch", find)
    with pytest.raises(ConfigError, match="package 'nope' not found"):
        resolve_launch_file("nope/launch/a.launch", find)
    with pytest.raises(ConfigError, match="not a"):
        resolve_launch_file("pkg/../pkg/launch/a.launch", find)


# ---------------------------------------------------------------------------------------------- the state machine
class Recorder:
    """Drives one machine and records every state change (from, to)."""

    def __init__(self, spec: ModuleSpec, clock: FakeClock) -> None:
        self.m = ModuleMachine(spec, clock)
        self.seen: set[tuple[str, str]] = set()
        self.state = self.m.state
        self.alive: set[str] = set()
        self.running = False

    def _track(self) -> str:
        s = self.m.state
        if s != self.state:
            self.seen.add((self.state, s))
            self.state = s
        return s

    def observe(self, *alive: str, running: Optional[bool] = None) -> str:
        self.alive = set(alive)
        if running is not None:
            self.running = running
        self.m.observe(self.alive, self.running)
        return self._track()

    def begin(self, target: str) -> str:
        self.m.begin(target)
        return self._track()

    def fail(self, msg: str) -> str:
        self.m.fail(msg)
        return self._track()

    def refresh(self) -> str:
        self.m.refresh()
        return self._track()


VISION = ModuleSpec("Vision", ("cell_bringup/launch/modules/vision.launch",), ("/a", "/b"), timeout_s=10)


def test_every_transition_of_the_four_states() -> None:
    clock = FakeClock()
    r = Recorder(VISION, clock)
    assert r.observe() == INACTIVE and r.m.status().message == "not running"

    # launched by the launcher: transitioning while the nodes come up, active once all answer
    assert r.begin(ACTIVE) == TRANSITIONING and r.m.status().target == ACTIVE
    assert r.m.status().message == "launching: 0 of 2 nodes up"
    clock.advance(0.5)
    assert r.observe("/a", running=True) == TRANSITIONING  # a partial launch is not incomplete yet
    assert r.m.status().message == "launching: 1 of 2 nodes up"
    assert r.observe("/a", "/b") == ACTIVE and r.m.status().target == ""
    assert r.m.status().alive == (True, True) and r.m.status().launched

    # killed and restarted from a terminal
    assert r.observe("/a") == INCOMPLETE and r.m.status().message == "not running: /b"
    assert r.m.status().alive == (True, False)
    assert r.observe("/a", "/b") == ACTIVE
    assert r.observe() == INACTIVE                      # every node killed from a terminal
    assert r.observe("/a", "/b", running=False) == ACTIVE   # all started from a terminal
    assert r.observe() == INACTIVE
    assert r.observe("/b") == INCOMPLETE                # one started from a terminal
    assert r.observe() == INACTIVE

    # stop: transitioning until every node is gone
    r.observe("/a", "/b")
    assert r.begin(INACTIVE) == TRANSITIONING and r.m.status().target == INACTIVE
    assert r.observe("/a") == TRANSITIONING and r.m.status().message == "stopping: 1 of 2 nodes still running"
    assert r.observe() == INACTIVE

    # launch and stop from incomplete
    r.observe("/a")
    assert r.begin(ACTIVE) == TRANSITIONING
    assert r.observe("/a", "/b") == ACTIVE
    r.observe("/b")
    assert r.state == INCOMPLETE
    assert r.begin(INACTIVE) == TRANSITIONING
    assert r.observe() == INACTIVE

    # the timeout: a launch that does not settle within timeout_s becomes incomplete
    assert r.begin(ACTIVE) == TRANSITIONING
    clock.advance(9.9)
    assert r.observe("/a") == TRANSITIONING
    clock.advance(0.1)
    assert r.refresh() == INCOMPLETE
    assert r.m.status().message == "launch did not complete within 10 s; not running: /b"
    assert r.m.status().target == ""

    # a launch that fails outright ends the transition: the state follows the liveness, with why
    r.observe()
    assert r.begin(ACTIVE) == TRANSITIONING
    assert r.fail("launch failed: no such launch file") == INACTIVE
    assert r.m.status().message == "launch failed: no such launch file"

    assert r.seen == {(a, b) for a in STATES for b in STATES if a != b}, sorted(r.seen)


def test_timed_out_transition_stays_incomplete_until_the_liveness_changes() -> None:
    clock = FakeClock()
    r = Recorder(VISION, clock)
    r.observe()
    r.begin(ACTIVE)
    clock.advance(10)
    assert r.observe() == INCOMPLETE  # nothing came up at all: a failed launch, not a quiet "inactive"
    msg = r.m.status().message
    assert msg == "launch did not complete within 10 s; not running: /a, /b"
    since = r.m.status().since
    clock.advance(30)
    assert r.observe() == INCOMPLETE and r.m.status().message == msg and r.m.status().since == since
    assert r.observe("/a", "/b") == ACTIVE  # started from a terminal later: followed again
    assert r.m.status().since == clock.t

    # a stop that does not settle: incomplete with the nodes still running, inactive once they are gone
    r.begin(INACTIVE)
    clock.advance(4)
    assert r.observe("/a", "/b") == TRANSITIONING
    clock.advance(6)
    assert r.observe("/a", "/b") == INCOMPLETE
    assert r.m.status().message == "stop did not complete within 10 s; still running: /a, /b"
    assert r.observe() == INACTIVE and r.m.status().message == "not running"


def test_a_stop_during_a_launch_takes_over_and_a_new_command_restarts_the_timer() -> None:
    clock = FakeClock()
    r = Recorder(VISION, clock)
    r.observe()
    r.begin(ACTIVE)
    clock.advance(8)
    r.observe("/a")
    assert r.begin(INACTIVE) == TRANSITIONING and r.m.status().target == INACTIVE
    clock.advance(8)  # 16 s after the launch, 8 s after the stop: not timed out
    assert r.observe("/a") == TRANSITIONING
    assert r.observe() == INACTIVE


def test_decisions() -> None:
    clock = FakeClock()
    m = ModuleMachine(VISION, clock)
    m.observe(set(), False)
    assert m.decide_launch() == (Decision.DO, "launching Vision")
    assert m.decide_stop() == (Decision.NOOP, "Vision is already inactive")
    m.observe(set(), True)  # every node died but the launcher still holds the launch: stop cleans it up
    assert m.decide_stop()[0] is Decision.DO
    m.begin(ACTIVE)
    assert m.decide_launch() == (Decision.NOOP, "Vision is already launching")
    assert m.decide_stop()[0] is Decision.DO
    m.begin(INACTIVE)
    assert m.decide_launch() == (Decision.REFUSE, "Vision is stopping: launch it once it is inactive")
    assert m.decide_stop() == (Decision.NOOP, "Vision is already stopping")
    m.observe({"/a", "/b"}, True)
    assert m.state == TRANSITIONING
    m.observe(set(), False)
    m.observe({"/a", "/b"}, False)
    assert m.state == ACTIVE and m.decide_launch() == (Decision.NOOP, "Vision is already active")
    assert m.decide_stop()[0] is Decision.DO  # started from a terminal: stop kills its nodes

    sim = ModuleMachine(ModuleSpec("Simulated cell", (), ("/sim_cell",)), clock)
    d, msg = sim.decide_launch()
    assert d is Decision.REFUSE and "cannot be launched" in msg and "no launch files" in msg
    d, msg = sim.decide_stop()
    assert d is Decision.REFUSE and "cannot be stopped" in msg
    sim.observe({"/sim_cell"}, False)
    assert sim.state == ACTIVE and sim.status().message == "its node is running"


def test_a_module_without_node_names_follows_the_launcher() -> None:
    clock = FakeClock()
    m = ModuleMachine(ModuleSpec("Bare", ("p/a.launch",), ()), clock)
    m.observe({"/other"}, False)
    assert m.state == INACTIVE and m.status().alive == ()
    m.begin(ACTIVE)
    assert m.state == TRANSITIONING
    m.observe(set(), True)
    assert m.state == ACTIVE and m.status().launched
    m.begin(INACTIVE)
    m.observe(set(), False)
    assert m.state == INACTIVE


# ---------------------------------------------------------------------------------------------- the manager
class FakeGraph:
    """The liveness source: the test (or the fake launcher) decides which nodes are alive."""

    def __init__(self) -> None:
        self.alive_nodes: set[str] = set()
        self.killed: list[str] = []
        self.down = False
        self.lock = threading.Lock()

    def alive(self, nodes: Any) -> set[str]:
        if self.down:
            raise GraphError("the ROS master does not answer")
        with self.lock:
            return {n for n in nodes if n in self.alive_nodes}

    def kill(self, nodes: Any) -> list[str]:
        with self.lock:
            self.killed += list(nodes)
            self.alive_nodes -= set(nodes)
        return list(nodes)


class FakeLauncher:
    def __init__(self, graph: FakeGraph, nodes: dict[str, tuple[str, ...]]) -> None:
        self.graph = graph
        self.nodes = nodes
        self.started: list[tuple[str, list]] = []
        self.stopped: list[str] = []
        self.running_names: set[str] = set()
        self.gate = threading.Event()
        self.gate.set()
        self.error: Optional[Exception] = None
        self.bring_up = True
        self.lines: dict[str, list[list[Line]]] = {}

    def start(self, name: str, files: Any) -> str:
        self.gate.wait(10)
        if self.error:
            raise self.error
        self.started.append((name, list(files)))
        self.running_names.add(name)
        if self.bring_up:
            with self.graph.lock:
                self.graph.alive_nodes |= set(self.nodes[name])
        return f"launched {name}"

    def stop(self, name: str) -> bool:
        if name not in self.running_names:
            return False
        self.running_names.discard(name)
        self.stopped.append(name)
        with self.graph.lock:
            self.graph.alive_nodes -= set(self.nodes[name])
        return True

    def running(self, name: str) -> bool:
        return name in self.running_names

    def output(self, name: str, lines: int) -> Optional[list[list[Line]]]:
        return self.lines.get(name)

    def shutdown(self) -> None:
        for n in list(self.running_names):
            self.stop(n)


SPECS = [ModuleSpec("Simulated cell", (), ("/sim_cell",)),
         ModuleSpec("Vision", ("pkg/launch/vision.launch",), ("/vision", "/vision_monitor"), timeout_s=10),
         ModuleSpec("Diagnostics", ("pkg/launch/diag.launch",), ("/system_monitor",), timeout_s=10)]


@pytest.fixture()
def rig():
    clock = FakeClock()
    graph = FakeGraph()
    launcher = FakeLauncher(graph, {s.name: s.nodes for s in SPECS})
    rosout = RosoutBuffer([n for s in SPECS for n in s.nodes])
    changes: list[int] = []
    mgr = ModulesManager(SPECS, launcher, graph, resolve=lambda ref: "/abs/" + ref,
                         launch_args=["cell_config:=/cells/demo.yaml"], rosout=rosout, clock=clock,
                         launch_wait_s=2.0, on_change=lambda: changes.append(1))
    yield mgr, launcher, graph, clock, rosout, changes
    launcher.gate.set()
    mgr.shutdown()


def state_of(mgr: ModulesManager, name: str) -> str:
    return next(s.state for s in mgr.statuses() if s.name == name)


def test_launch_poll_and_stop(rig) -> None:
    mgr, launcher, graph, clock, _rosout, changes = rig
    assert [s.state for s in mgr.poll()] == [INACTIVE] * 3
    ok, msg = mgr.launch("Vision")
    assert (ok, msg) == (True, "launched Vision")
    assert launcher.started == [("Vision", [("/abs/pkg/launch/vision.launch", ["cell_config:=/cells/demo.yaml"])])]
    assert changes, "the state must be published at once when a launch is accepted"
    assert state_of(mgr, "Vision") == TRANSITIONING  # until the next check sees the nodes
    assert mgr.poll()[1].state == ACTIVE and mgr.statuses()[1].launched
    assert mgr.launch("Vision") == (True, "Vision is already active")
    assert len(launcher.started) == 1

    n = len(changes)
    assert mgr.stop("Vision") == (True, "stopping Vision")
    assert len(changes) > n
    wait_for(lambda: launcher.stopped == ["Vision"], 5, what="the worker stopping Vision")
    assert mgr.poll()[1].state == INACTIVE and not mgr.statuses()[1].launched
    assert graph.killed == []  # nothing was left for rosnode-kill: the launcher's shutdown took them all


def test_names_not_in_the_cell_file_are_refused(rig) -> None:
    mgr, launcher, _g, _c, _r, _ch = rig
    for call in (mgr.launch, mgr.stop):
        ok, msg = call("../../etc/passwd")
        assert not ok and msg == ("unknown module '../../etc/passwd' (the cell has: Simulated cell, Vision, "
                                  "Diagnostics)")
    ok, msg, lines = mgr.output("vision", 10)  # names are exact
    assert not ok and "unknown module 'vision'" in msg and lines == []
    assert launcher.started == []


def test_monitor_only_modules_cannot_be_launched_or_stopped(rig) -> None:
    mgr, launcher, graph, _c, _r, _ch = rig
    graph.alive_nodes.add("/sim_cell")
    mgr.poll()
    ok, msg = mgr.launch("Simulated cell")
    assert not ok and "cannot be launched" in msg
    ok, msg = mgr.stop("Simulated cell")
    assert not ok and "cannot be stopped" in msg
    assert graph.killed == [] and launcher.started == [] and state_of(mgr, "Simulated cell") == ACTIVE


def test_stop_kills_nodes_started_from_a_terminal(rig) -> None:
    mgr, launcher, graph, _c, _r, _ch = rig
    graph.alive_nodes |= {"/vision", "/vision_monitor", "/unrelated"}
    assert mgr.poll()[1].state == ACTIVE and not mgr.statuses()[1].launched
    assert mgr.stop("Vision") == (True, "stopping Vision")
    wait_for(lambda: sorted(graph.killed) == ["/vision", "/vision_monitor"], 5, what="rosnode kill of its nodes")
    assert launcher.stopped == []
    assert mgr.poll()[1].state == INACTIVE and "/unrelated" in graph.alive_nodes


def test_a_failed_launch_answers_why_and_ends_the_transition(rig) -> None:
    mgr, launcher, _g, _c, _r, _ch = rig
    launcher.error = LaunchError("launch failed: cannot locate node of type [vision_node]")
    assert mgr.launch("Vision") == (False, "launch failed: cannot locate node of type [vision_node]")
    st = mgr.poll()[1]
    assert st.state == INACTIVE and st.message == "launch failed: cannot locate node of type [vision_node]"

    launcher.error = None
    mgr.resolve = lambda ref: (_ for _ in ()).throw(ConfigError(f"{ref}: no such launch file in 'pkg'"))
    ok, msg = mgr.launch("Vision")
    assert not ok and msg == "launch failed: pkg/launch/vision.launch: no such launch file in 'pkg'"
    assert state_of(mgr, "Vision") == INACTIVE and launcher.started == []


def test_a_slow_launch_blocks_neither_the_services_nor_the_check(rig) -> None:
    mgr, launcher, graph, _clock, _r, _ch = rig
    mgr.launch_wait_s = 0.2
    launcher.gate.clear()  # roslaunch hangs
    t0 = time.monotonic()
    assert mgr.launch("Vision") == (True, "launching Vision: roslaunch is still starting it")
    assert time.monotonic() - t0 < 1.0
    graph.alive_nodes |= {"/sim_cell", "/system_monitor"}
    t0 = time.monotonic()
    assert [s.state for s in mgr.poll()] == [ACTIVE, TRANSITIONING, ACTIVE]
    assert mgr.output("Vision", 5)[0]
    # another module has its own worker: its stop is not queued behind Vision's launch
    assert mgr.stop("Diagnostics") == (True, "stopping Diagnostics")
    wait_for(lambda: graph.killed == ["/system_monitor"], 2, what="Diagnostics stopped meanwhile")
    # Vision's stop is accepted at once, and runs after its launch in Vision's worker
    assert mgr.stop("Vision") == (True, "stopping Vision")
    assert time.monotonic() - t0 < 2.0
    assert launcher.stopped == [] and launcher.started == []
    launcher.gate.set()
    wait_for(lambda: launcher.stopped == ["Vision"], 5, what="the stop after the launch")
    assert [name for name, _ in launcher.started] == ["Vision"]
    assert [s.state for s in mgr.poll()] == [ACTIVE, INACTIVE, INACTIVE]


def test_a_launch_that_does_not_come_up_times_out_to_incomplete(rig) -> None:
    mgr, launcher, graph, clock, _r, _ch = rig
    launcher.bring_up = False
    assert mgr.launch("Vision")[0]
    graph.alive_nodes.add("/vision")
    assert mgr.poll()[1].state == TRANSITIONING
    clock.advance(10)
    st = mgr.poll()[1]
    assert st.state == INCOMPLETE and st.message == "launch did not complete within 10 s; not running: /vision_monitor"
    # relaunching an incomplete module replaces the launcher's previous launch
    launcher.bring_up = True
    assert mgr.launch("Vision")[0]
    assert launcher.stopped == ["Vision"] and len(launcher.started) == 2
    assert mgr.poll()[1].state == ACTIVE


def test_without_a_master_the_states_stay_and_timeouts_still_run(rig) -> None:
    mgr, launcher, graph, clock, _r, _ch = rig
    launcher.bring_up = False
    mgr.launch("Vision")
    graph.alive_nodes.add("/system_monitor")
    mgr.poll()
    graph.down = True
    assert [s.state for s in mgr.poll()] == [INACTIVE, TRANSITIONING, ACTIVE] and not mgr.master_ok
    clock.advance(11)
    assert [s.state for s in mgr.poll()] == [INACTIVE, INCOMPLETE, ACTIVE]
    graph.down = False
    mgr.poll()
    assert mgr.master_ok


def test_output_from_the_launcher_or_from_rosout(rig) -> None:
    mgr, launcher, graph, _c, rosout, _ch = rig
    launcher.lines["Vision"] = [[Line(1.0, "[vision] a"), Line(3.0, "[vision] c")],
                                [Line(2.0, "[vision_monitor] b")], [Line(4.0, "[launcher] d")]]
    ok, msg, lines = mgr.output("Vision", 3)
    assert ok and lines == ["[vision_monitor] b", "[vision] c", "[launcher] d"]
    assert msg == "3 lines of Vision: its nodes' output since its latest launch"

    rosout.add("/system_monitor", "INFO", 5.5, "hello")
    rosout.add("/system_monitor", "ERROR", 6.0, "boom\nTraceback (most recent call last):\n  File x")
    rosout.add("/elsewhere", "INFO", 6.5, "not ours")
    ok, msg, lines = mgr.output("Diagnostics", 0)
    assert ok and "/rosout" in msg
    assert lines == ["[system_monitor] [INFO] [5.500000]: hello", "[system_monitor] [ERROR] [6.000000]: boom",
                     "[system_monitor] Traceback (most recent call last):", "[system_monitor]   File x"]
    assert mgr.output("Simulated cell", 10) == (True, "0 lines of Simulated cell: its nodes' /rosout messages "
                                                      "(not launched by the modules node)", [])


# ---------------------------------------------------------------------------------------------- output
def test_tail_and_merge_are_bounded_and_ordered(tmp_path: Path) -> None:
    assert clamp_lines(0) == MAX_LINES == clamp_lines(10_000) and clamp_lines(7) == 7 and clamp_lines(-1) == 200
    big = tmp_path / "big.log"
    big.write_text("".join(f"line {i}\n" for i in range(100_000)))
    t0 = time.monotonic()
    assert tail_file(str(big), 3) == ["line 99997", "line 99998", "line 99999"]
    assert len(tail_file(str(big), 10_000)) < 10_000  # never more than the last 64 KiB
    assert time.monotonic() - t0 < 0.5
    assert tail_file(str(tmp_path / "missing.log"), 5) == []
    (tmp_path / "long.log").write_text("x" * 5000 + "\n")
    assert len(tail_file(str(tmp_path / "long.log"), 1)[0]) == 500

    out = tmp_path / "vision-1-stdout.log"
    out.write_text("[INFO] [100.5]: started\nplain print\n[WARN] [102.0]: late\n")
    err = tmp_path / "vision-1-stderr.log"
    err.write_text("Traceback (most recent call last):\n  boom\n")
    os.utime(err, (101.0, 101.0))
    groups = [stream_lines(Stream("[vision]", str(out)), 10), stream_lines(Stream("[vision stderr]", str(err)), 10)]
    assert merge(groups, 10) == ["[vision] [INFO] [100.5]: started", "[vision] plain print",
                                 "[vision stderr] Traceback (most recent call last):", "[vision stderr]   boom",
                                 "[vision] [WARN] [102.0]: late"]
    assert merge(groups, 2) == ["[vision stderr]   boom", "[vision] [WARN] [102.0]: late"]


def test_rosout_buffer_keeps_the_last_lines_of_watched_nodes_only() -> None:
    buf = RosoutBuffer(["/a"], per_node=3)
    for i in range(5):
        buf.add("/a", "INFO", float(i), f"m{i}")
    buf.add("/b", "INFO", 9.0, "other")
    (a, b) = buf.lines(["/a", "/b"])
    assert [x.text for x in a] == ["[a] [INFO] [2.000000]: m2", "[a] [INFO] [3.000000]: m3",
                                   "[a] [INFO] [4.000000]: m4"]
    assert b == []


# ---------------------------------------------------------------------------------------------- liveness
class _NodeApi:
    """A node's XML-RPC API: answers getPid, records shutdown."""

    def __init__(self) -> None:
        self.server = SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False, allow_none=True)
        self.uri = "http://127.0.0.1:%d/" % self.server.server_address[1]
        self.shutdowns: list[str] = []
        self.server.register_function(lambda caller: [1, "", os.getpid()], "getPid")
        self.server.register_function(self._shutdown, "shutdown")
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def _shutdown(self, caller: str, reason: str) -> list:
        self.shutdowns.append(reason)
        return [1, "", 0]

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


class _FakeMaster:
    def __init__(self, nodes: dict[str, str]) -> None:
        self.nodes = dict(nodes)   # name -> API URI
        self.calls: list[tuple] = []
        self.server = SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False, allow_none=True)
        self.uri = "http://127.0.0.1:%d/" % self.server.server_address[1]
        s = self.server
        s.register_function(self.getSystemState, "getSystemState")
        s.register_function(self.lookupNode, "lookupNode")
        s.register_function(lambda caller, srv: [1, "", f"rosrpc://svc/{srv}"], "lookupService")
        for name in ("unregisterPublisher", "unregisterSubscriber", "unregisterService", "unsubscribeParam"):
            s.register_function(self._recorder(name), name)
        threading.Thread(target=s.serve_forever, daemon=True).start()

    def _recorder(self, name: str):
        def f(caller: str, what: str, api: str) -> list:
            self.calls.append((name, caller, what, api))
            return [1, "", 1]
        return f

    def getSystemState(self, caller: str) -> list:
        names = sorted(self.nodes)
        return [1, "", [[["/rosout", names]], [["/clock", names[:1]]], [[f"{names[0]}/get_loggers", names[:1]]]]]

    def lookupNode(self, caller: str, name: str) -> list:
        return [1, "", self.nodes[name]] if name in self.nodes else [-1, "unknown node", ""]

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_liveness_pings_cleans_dead_nodes_and_stays_bounded() -> None:
    live = _NodeApi()
    # a hung node: its port accepts connections (the kernel's backlog) but nobody ever answers
    hung = [socket.socket() for _ in range(3)]
    for h in hung:
        h.bind(("127.0.0.1", 0))
        h.listen(5)
    dead_uri = "http://127.0.0.1:%d/" % _closed_port()
    nodes = {"/a_dead": dead_uri, "/live": live.uri,
             **{f"/hung{i}": "http://127.0.0.1:%d/" % h.getsockname()[1] for i, h in enumerate(hung)}}
    master = _FakeMaster(nodes)
    graph = MasterGraph(master.uri, "/modules", ping_timeout=0.5)
    try:
        t0 = time.monotonic()
        alive = graph.alive(["/live", "/a_dead", "/hung0", "/hung1", "/hung2", "/not_registered"])
        took = time.monotonic() - t0
        assert alive == {"/live"}
        assert took < 1.5, f"one check took {took:.2f} s with three hung nodes (pings must run in parallel)"
        # the dead node's registrations were removed, as itself and with its own URI; the hung ones were left alone
        assert sorted(master.calls) == [
            ("unregisterPublisher", "/a_dead", "/rosout", dead_uri),
            ("unregisterService", "/a_dead", "/a_dead/get_loggers", "rosrpc://svc//a_dead/get_loggers"),
            ("unregisterSubscriber", "/a_dead", "/clock", dead_uri),
            ("unsubscribeParam", "/a_dead", dead_uri, "/rosout_disable_topics_generation")]
        assert graph.cleaned == ["/a_dead"]

        assert graph.kill(["/live", "/not_registered"]) == ["/live"]
        assert live.shutdowns == ["stopped by the modules node"]
    finally:
        graph.close()
        master.close()
        live.close()
        for h in hung:
            h.close()


def test_liveness_without_a_master_raises_graph_error() -> None:
    graph = MasterGraph("http://127.0.0.1:%d/" % _closed_port(), "/modules", master_timeout=0.5)
    try:
        with pytest.raises(GraphError, match="does not answer"):
            graph.alive(["/x"])
    finally:
        graph.close()


# ---------------------------------------------------------------------------------------------- the demo nodes
def _jpeg(grey: int) -> bytes:
    from PIL import Image
    buf = io.BytesIO()
    Image.new("RGB", (64, 48), (grey, grey, grey)).save(buf, "JPEG")
    return buf.getvalue()


def test_demo_vision_brightness_and_status() -> None:
    assert demo.mean_brightness(_jpeg(0)) < 0.02
    assert demo.mean_brightness(_jpeg(255)) > 0.98
    assert demo.mean_brightness(_jpeg(128)) == pytest.approx(128 / 255, abs=0.02)
    with pytest.raises(Exception):
        demo.mean_brightness(b"not an image")
    assert demo.vision_status(None, 0) == "no image"
    assert demo.vision_status(0.5, 3.5) == "no image"
    assert demo.vision_status(0.05, 0.1) == "dark"
    assert demo.vision_status(0.95, 0.1) == "overexposed"
    assert demo.vision_status(0.5, 0.1) == "ok"


def test_demo_vision_topic_comes_from_the_cell_file() -> None:
    cell = yaml.safe_load(DEMO.read_text())
    assert demo.stream_topic(cell, "Workbench") == "/cell/camera/workbench/image/compressed"
    assert demo.stream_topic(cell, "") == cell["video"]["streams"][0]["topic"]
    with pytest.raises(ValueError, match="no video stream named 'Nope'"):
        demo.stream_topic(cell, "Nope")
    assert 0 <= demo.load_per_core() < 100
