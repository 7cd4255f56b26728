"""Operation mode: the pure state machine, and the node on a live ROS graph: the node tests' bodies run on ROS 1
(a roscore) and on ROS 2 (scripts/test-all.sh runs this file under .venv-ros2), the peer through our wiring."""
from __future__ import annotations

import os
import threading
from typing import Any, List

import pytest

from cell_nodes.operation_mode import OperationMode
from conftest import wait_for
from nodes_helpers import Nodes, peer

CELL = os.path.join(os.path.dirname(__file__), "../../../../config/demo-cell.yaml")
MODES = ["idle", "running", "paused", "alarm", "programming", "manual"]


def test_state_machine_accepts_listed_modes_and_refuses_others() -> None:
    m = OperationMode(MODES, "idle")
    assert m.state.mode == "idle"
    assert m.set("running", "ui:alice") == (True, "mode is now running")
    ok, why = m.set("flying", "ui:bob")
    assert not ok and "flying" in why and "idle" in why
    assert m.state.mode == "running" and m.state.source == "ui:alice"


def test_a_change_unless_the_mode_is_one_given_is_checked_with_the_change() -> None:
    """The process sets `idle` when its run ended, unless the alarms node set `alarm` in the meantime."""
    m = OperationMode(MODES, "running")
    assert m.set("alarm", "alarms") == (True, "mode is now alarm")
    ok, why = m.set("idle", "process", unless=["alarm"])
    assert not ok and why == "the mode is alarm (set by alarms): not changed to idle"
    assert (m.state.mode, m.state.source) == ("alarm", "alarms")
    assert m.set("manual", "ui:alice")[0]                      # anyone else still may (an operator recovering)
    assert m.set("idle", "process", unless=["alarm"]) == (True, "mode is now idle")


def test_state_machine_rejects_bad_initial() -> None:
    with pytest.raises(ValueError):
        OperationMode(MODES, "flying")
    with pytest.raises(ValueError):
        OperationMode([], None)


def echo_mode() -> str:
    """The mode a new subscriber of the topic hears first (the latched one), as `rostopic echo -n 1` would."""
    from cell_msgs.msg import OperationMode as OperationModeMsg
    got: List[Any] = []
    heard = threading.Event()
    sub = peer().subscribe("/cell/mode", OperationModeMsg, lambda m, _s: (got.append(m), heard.set()), latched=True)
    try:
        assert heard.wait(15), "nothing latched on /cell/mode"
        return got[0].mode
    finally:
        sub.close()


@pytest.fixture()
def mode_node(ros_graph: str):
    nodes = Nodes()
    node = nodes.run("operation_mode", "operation_mode_node", f"_cell_config:={os.path.abspath(CELL)}",
                     "__name:=operation_mode_test")
    try:
        nodes.wait_ready("/cell/get_mode", timeout=20)
        yield node.proc
    finally:
        nodes.stop()
        nodes.check()


def test_node_publishes_latched_mode_and_serves_get_set(mode_node) -> None:
    from cell_msgs.srv import GetMode, SetMode

    get = peer().client("/cell/get_mode", GetMode)
    set_ = peer().client("/cell/set_mode", SetMode)
    assert get().mode == "idle"
    assert echo_mode() == "idle"  # latched: a late subscriber gets it

    r = set_(mode="manual", source="test")
    assert r.success, r.message
    assert get().mode == "manual" and get().source == "test"
    assert echo_mode() == "manual"

    bad = set_(mode="flying", source="test")
    assert not bad.success and "flying" in bad.message
    assert get().mode == "manual"
    kept = set_(mode="idle", source="process", unless_mode=["manual"])
    assert not kept.success and get().mode == "manual"


def test_node_adopts_a_mode_published_from_outside(mode_node) -> None:
    from cell_msgs.msg import OperationMode as OperationModeMsg
    from cell_msgs.srv import GetMode

    get = peer().client("/cell/get_mode", GetMode)
    pub = peer().publisher("/cell/mode", OperationModeMsg, queue_size=1)
    try:
        # published until the node hears it (a new publisher's first messages may precede the connection)
        wait_for(lambda: pub.publish(OperationModeMsg(mode="running", source="terminal")) and get().mode == "running",
                 10, what="mode adopted")
        assert get().source == "terminal"
    finally:
        pub.close()
