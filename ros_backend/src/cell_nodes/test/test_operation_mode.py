"""Operation mode: the pure state machine, and the node against a live roscore."""
from __future__ import annotations

import os
import subprocess

import pytest
import rospy

from cell_nodes.operation_mode import OperationMode
from conftest import wait_for
from nodes_helpers import Nodes

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
    out = subprocess.run(["rostopic", "echo", "-n", "1", "/cell/mode/mode"], capture_output=True, text=True, timeout=15)
    return out.stdout.split("\n")[0].strip().strip('"')


@pytest.fixture()
def mode_node(roscore: str):
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

    get = rospy.ServiceProxy("/cell/get_mode", GetMode)
    set_ = rospy.ServiceProxy("/cell/set_mode", SetMode)
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
    from cell_msgs.srv import GetMode

    get = rospy.ServiceProxy("/cell/get_mode", GetMode)
    subprocess.run(["rostopic", "pub", "-1", "/cell/mode", "cell_msgs/OperationMode", "{mode: running, source: terminal}"],
                   check=True, timeout=20, capture_output=True)
    wait_for(lambda: get().mode == "running", 10, what="mode adopted")
    assert get().source == "terminal"
