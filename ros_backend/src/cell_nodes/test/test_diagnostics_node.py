"""Diagnostics on a live roscore: this test publishes diagnostic_msgs/DiagnosticArray on /diagnostics as a driver
would. The alarms node (`alarms.diagnostics` rules) raises the warning, then the stale alarm when the status falls
silent, and clears it when it reports again; the inspect node's /cell/inspect/diagnostics shows the same statuses
with the silent one STALE."""
from __future__ import annotations

import threading
from pathlib import Path
from typing import Iterator

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node

ROOT = Path(__file__).resolve().parents[4]
NAME = "diag_test: widget"
ALARM = "diagnostics.diag_test_widget"


class Reporter:
    """Publishes one status at 5 Hz while `level` is not None."""

    def __init__(self) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        self.pub = rospy.Publisher("/diagnostics", DiagnosticArray, queue_size=10)
        self.level, self.message = None, ""
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
        while not self._stop.wait(0.2):
            if self.level is not None:
                self.pub.publish(DiagnosticArray(status=[DiagnosticStatus(
                    level=self.level, name=NAME, message=self.message, values=[KeyValue(key="rate", value="5")])]))

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2)


@pytest.fixture(scope="module")
def nodes(roscore: str, tmp_path_factory) -> Iterator[Reporter]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc.pop("manual", None)   # no robot driver here: no robot alarms in the way
    doc["alarms"] = {"alarm_mode": "", "diagnostics": {"stale_s": 1.5, "rules": [
        {"match": "diag_test: *", "warn": "warning", "stale": "error"}]}}
    path = tmp_path_factory.mktemp("diagnostics") / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    client_node("diagnostics_test_client")
    n = Nodes()
    n.run("alarms", "alarms_node", f"_cell_config:={path}", "__name:=alarms_diag_test")
    n.run("inspect", "inspect_node", f"_cell_config:={path}", "__name:=inspect_diag_test")
    reporter = None
    try:
        n.wait_ready("/cell/alarms/reset", "/cell/inspect/graph", what="the alarms and inspect nodes")
        reporter = Reporter()
        yield reporter
    finally:
        if reporter:
            reporter.stop()
        n.stop()
        n.check()


def test_warn_then_stale_then_clear_as_alarms_and_in_the_inspect_tree(nodes: Reporter) -> None:
    from cell_msgs.msg import AlarmList
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    latest: dict = {}
    subs = [rospy.Subscriber("/cell/alarms/list", AlarmList, lambda m: latest.__setitem__("alarms", m)),
            rospy.Subscriber("/cell/inspect/diagnostics", DiagnosticArray, lambda m: latest.__setitem__("tree", m))]

    def alarm():
        return next((a for a in latest["alarms"].alarms if a.id == ALARM), None) if "alarms" in latest else None

    def tree_level():
        s = next((s for s in latest["tree"].status if s.name == NAME), None) if "tree" in latest else None
        return None if s is None else s.level

    try:
        nodes.level, nodes.message = DiagnosticStatus.WARN, "slow"
        wait_for(lambda: alarm() is not None and alarm().active, 10, what="the warning as an alarm")
        a = alarm()
        assert (a.severity, a.text, a.source) == (1, f"{NAME}: slow", "diagnostics")
        wait_for(lambda: tree_level() == DiagnosticStatus.WARN, 5, what="the warning in the inspect tree")

        nodes.level = None                    # silent: stale after 1.5 s (alarms), 5 s (the inspect tree)
        wait_for(lambda: alarm().severity == 2 and "no report for 1.5 s" in alarm().text, 10, what="the stale alarm")
        wait_for(lambda: tree_level() == DiagnosticStatus.STALE, 10, what="STALE in the inspect tree")

        nodes.level, nodes.message = DiagnosticStatus.OK, "fine"
        wait_for(lambda: not alarm().active, 10, what="the alarm inactive once it reports OK again")
        wait_for(lambda: tree_level() == DiagnosticStatus.OK, 5, what="OK in the inspect tree")
    finally:
        for s in subs:
            s.unregister()
