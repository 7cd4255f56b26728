"""The inspect node on a live roscore (its rosout node aggregates /rosout into /rosout_agg): `rosrun cell_nodes
inspect_node` with a cell file keeping 50 entries. A warning this test's node logs with rospy.logwarn is in the
history with its node, level, file and line; the filters narrow it; a storm keeps the newest 50. A bad section
stops the node at once, naming the field."""
from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Iterator

import pytest
import rospy
import yaml

from conftest import wait_for
from nodes_helpers import Nodes, client_node

ROOT = Path(__file__).resolve().parents[4]
TAG = "inspect_test"


@pytest.fixture(scope="module")
def inspect(roscore: str, tmp_path_factory) -> Iterator[None]:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["inspect"] = {"log_keep_entries": 50, "log_keep_s": 600}
    path = tmp_path_factory.mktemp("inspect") / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
    client_node(f"{TAG}_client")
    nodes = Nodes()
    node = nodes.run("inspect", "inspect_node", f"_cell_config:={path}", f"__name:={TAG}")
    try:
        nodes.wait_ready("/cell/inspect/log", what="the inspect node's log service")
        yield
    finally:
        nodes.stop()
        print(f"\ninspect log:\n{node.tail()}")
        nodes.check()


def query(**kw):
    from cell_msgs.srv import LogQuery
    return rospy.ServiceProxy("/cell/inspect/log", LogQuery)(**kw)


def test_a_warning_a_node_logs_is_kept_with_its_node_level_and_place(inspect: None) -> None:
    from cell_msgs.msg import RosLogEntry
    me = rospy.get_name()
    wait_for(lambda: query(node=me).matched > 0 or rospy.loginfo("inspect test: hello") or False, 10,
             what="this node's log reaching the inspect node")
    rospy.logwarn("inspect test: the gripper is slow (%d ms)", 420)
    wait_for(lambda: query(text="gripper is slow").matched == 1, 10, what="the warning in the history")
    [e] = query(text="GRIPPER IS SLOW").entries
    assert (e.level, e.node, e.msg) == (RosLogEntry.WARN, me, "inspect test: the gripper is slow (420 ms)")
    assert e.file.endswith("test_inspect_node.py") and e.line > 0 and e.stamp.to_sec() > 0
    assert query(text="gripper is slow", min_level=RosLogEntry.ERROR).matched == 0
    assert query(text="gripper is slow", node="/someone_else").matched == 0
    assert all(x.level >= RosLogEntry.WARN for x in query(min_level=RosLogEntry.WARN).entries)


def test_a_storm_keeps_the_newest_entries(inspect: None) -> None:
    for i in range(200):
        rospy.loginfo("inspect test: storm %d", i)
    wait_for(lambda: any(e.msg == "inspect test: storm 199" for e in query(text="storm").entries), 10,
             what="the storm's last entry")
    r = query()
    assert len(r.entries) <= 50 and r.dropped >= 150
    capped = query(text="storm", max_entries=3)
    assert [e.msg for e in capped.entries] == [f"inspect test: storm {i}" for i in (197, 198, 199)]


def test_a_bad_section_stops_the_node_naming_the_field(roscore: str, tmp_path: Path) -> None:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["inspect"] = {"log_keep_s": 0}
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(doc))
    out = subprocess.run(["rosrun", "cell_nodes", "inspect_node", f"_cell_config:={path}", "__name:=inspect_bad"],
                         capture_output=True, text=True, timeout=30)
    assert out.returncode == 2, (out.stdout, out.stderr)
    assert "inspect.log_keep_s: expected a number from 1 to 86400, got 0" in out.stdout + out.stderr
