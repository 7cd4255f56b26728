"""The process keeps its cycle counter and last cycle times across a restart of its nodes, and reports a cycle's time
with and without its pauses (issue 28 "Nothing lost"): roscore + the operation-mode node + `rosrun cell_nodes
process_server` + `rosrun cell_nodes process_node` with their own DATA_DIR, runs in dry run (no robot needed). The
nodes are killed (SIGKILL: no shutdown code runs, as in a power cut) and started again. A malformed state file is
logged and the process counts from cycle 1."""
from __future__ import annotations

import json
import os
import re
import threading
import time
from pathlib import Path
from typing import Any, Iterator

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Node, Nodes, client_node

ROOT = Path(__file__).resolve().parents[4]
TAG = "process_restart_test"
STEP_S = 0.1      # dry_run_step_s: the demo cell's 13 steps make a 1.3 s cycle


class Latest:
    def __init__(self, topic: str, mtype: Any) -> None:
        self.msg: Any = None
        self.msgs: list[Any] = []
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, mtype, self._cb, queue_size=200)

    def _cb(self, msg: Any) -> None:
        with self._lock:
            self.msg = msg
            self.msgs.append(msg)


@pytest.fixture(scope="module")
def cell(roscore: str, tmp_path_factory) -> Iterator[dict]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["process"]["dry_run_step_s"] = STEP_S
    base = tmp_path_factory.mktemp("process-restart")
    path = base / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    data_dir = base / "data"
    env = dict(os.environ, DATA_DIR=str(data_dir), PYTHONUNBUFFERED="1")
    env.pop("CELL_CONFIG", None)
    client_node(f"{TAG}_client")
    from cell_msgs.msg import LogEntries, ProcessState
    mode = Nodes()
    mode_node = mode.run("operation_mode", "operation_mode_node", f"_cell_config:={path}", f"__name:={TAG}_mode",
                         env=env)
    nodes: dict[str, Node] = {}
    state = Latest("/cell/process/state", ProcessState)
    log = Latest("/cell/process/log", LogEntries)

    def start() -> dict[str, Node]:
        state.msg = None
        procs = Nodes()
        nodes["server"] = procs.run("process_server", "process_server", f"_cell_config:={path}",
                                    f"__name:={TAG}_server", env=env)
        nodes["client"] = procs.run("process_node", "process_node", f"_cell_config:={path}",
                                    f"__name:={TAG}_client_node", env=env)
        procs.wait_ready("/cell/process/start", what="the process nodes' services")
        wait_for(lambda: state.msg is not None and state.msg.ready, 15, what="the client seeing the action server")
        return nodes

    def kill() -> None:
        killed = [nodes.pop(name) for name in list(nodes)]
        for node in killed:
            node.kill()
        for node in killed:
            node.check()

    try:
        mode.wait_ready("/cell/set_mode", what="the operation-mode node")
        yield {"start": start, "kill": kill, "nodes": nodes, "state": state, "log": log,
               "state_file": data_dir / "state" / "process.json"}
    finally:
        state.sub.unregister()
        log.sub.unregister()
        ends = [*nodes.values(), mode_node]
        for node in ends:   # one after the other: the process server, its client, the mode node
            node.stop()
        for node in ends:
            node.check()


def _texts(log: Latest) -> list[str]:
    return [e.text for e in log.msg.entries] if log.msg else []


def test_cycle_times_with_and_without_pauses_and_the_counter_survives_a_power_cut(cell: dict) -> None:
    from std_srvs.srv import SetBool, Trigger
    from cell_msgs.srv import ProcessStart
    state: Latest = cell["state"]
    cell["start"]()
    s = state.msg
    assert (s.cycle, s.last_cycle_s, s.last_cycle_elapsed_s) == (1, 0.0, 0.0)       # nothing saved yet
    assert rospy.ServiceProxy("/cell/process/set_dry_run", SetBool)(True).success
    assert rospy.ServiceProxy("/cell/process/start", ProcessStart)(cycles=1).success
    assert rospy.ServiceProxy("/cell/process/pause", Trigger)().success
    wait_for(lambda: state.msg.state == "paused", 5, what="paused")
    time.sleep(0.3)                                                   # a state message from inside the pause
    a = state.msg
    time.sleep(1.2)                                                   # paused: the active time stands still
    b = state.msg
    assert b.state == "paused" and b.cycle_time_s == pytest.approx(a.cycle_time_s, abs=0.02)
    assert b.cycle_elapsed_s - a.cycle_elapsed_s >= 0.6                           # (2 Hz messages)
    assert b.cycle_elapsed_s - b.cycle_time_s >= 0.9
    assert rospy.ServiceProxy("/cell/process/resume", Trigger)().success
    wait_for(lambda: state.msg.state == "idle", 10, what="the run's end")
    s = state.msg
    assert (s.cycle, s.cycles_done, s.message) == (2, 1, "1 cycle done")
    assert 13 * STEP_S * 0.9 < s.last_cycle_s < 13 * STEP_S + 1.0                   # the steps only
    assert s.last_cycle_elapsed_s - s.last_cycle_s >= 1.4                          # plus the pause
    wait_for(lambda: any(t.startswith("Cycle 1 done in") for t in _texts(cell["log"])), 3, what="the cycle line")
    line = next(t for t in _texts(cell["log"]) if t.startswith("Cycle 1 done in"))
    assert re.fullmatch(r"Cycle 1 done in \d+\.\d s \(\d+\.\d s with pauses\)", line), line
    saved = json.loads(cell["state_file"].read_text())
    assert saved["kind"] == "process.cycles" and saved["data"] == {
        "next_cycle": 2, "last_cycle_s": s.last_cycle_s, "last_cycle_elapsed_s": s.last_cycle_elapsed_s}
    before = (s.last_cycle_s, s.last_cycle_elapsed_s)

    cell["kill"]()                                                    # both nodes at once, no shutdown code
    cell["start"]()
    s = cell["state"].msg
    # Before this feature: cycle 1 again (the pose tables started over at the first part) and no last cycle time.
    assert (s.state, s.cycle, s.cycles_done) == ("idle", 2, 0)
    assert (s.last_cycle_s, s.last_cycle_elapsed_s) == before
    wait_for(lambda: "Restored after a restart: the next cycle is 2" in " ".join(_texts(cell["log"])), 3,
             what="the restore in the page's log")
    restored = next(e for e in cell["log"].msg.entries if e.text.startswith("Restored after a restart"))
    assert restored.code == "process.restored" and ("cycle", "2") in [(kv.key, kv.value) for kv in restored.params]
    assert rospy.ServiceProxy("/cell/process/set_dry_run", SetBool)(True).success
    r = rospy.ServiceProxy("/cell/process/start", ProcessStart)(cycles=1)
    assert (r.success, r.message) == (True, "started: 1 cycle from cycle 2 (dry run)")
    wait_for(lambda: state.msg.state == "idle" and state.msg.cycle == 3, 10, what="cycle 2 done")
    assert json.loads(cell["state_file"].read_text())["data"]["next_cycle"] == 3


def test_a_malformed_state_file_is_logged_and_the_process_counts_from_1(cell: dict) -> None:
    cell["kill"]()
    state_file: Path = cell["state_file"]
    state_file.write_text(json.dumps({"kind": "process.cycles", "version": 1,
                                      "data": {"next_cycle": -4, "last_cycle_s": 1.0, "last_cycle_elapsed_s": 1.0}}))
    nodes = cell["start"]()
    s = cell["state"].msg
    assert (s.cycle, s.last_cycle_s) == (1, 0.0)
    wait_for(lambda: "process state:" in nodes["client"].output(), 5, what="the problem in the node's log")
    out = nodes["client"].output()
    assert f"{state_file}: next_cycle: expected a whole number from 1 to 4294967295, got -4; starting clean" in out
    assert state_file.with_name("process.json.bad").exists()
    wait_for(lambda: any(t.startswith("The saved cycle counter could not be used") for t in _texts(cell["log"])), 3,
             what="the problem in the page's log")
    wait_for(lambda: state_file.exists() and json.loads(state_file.read_text())["data"]["next_cycle"] == 1, 3,
             what="a clean state file")
