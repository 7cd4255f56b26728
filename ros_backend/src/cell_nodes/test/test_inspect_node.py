"""The inspect node on a live roscore (its rosout node aggregates /rosout into /rosout_agg): `rosrun cell_nodes
inspect_node` with a cell file keeping 50 entries. A warning this test's node logs with rospy.logwarn is in the
history with its node, level, file and line; the filters narrow it; a storm keeps the newest 50. The graph lists
this test's topic and node (with the module the cell file gives it); a 50 Hz topic measures 50 Hz; its last message
comes back as JSON; the subscription ends when nobody asks. A bad section stops the node at once, naming the field."""
from __future__ import annotations

import json
import subprocess
import threading
import time
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
    client_node(f"{TAG}_client")
    doc["modules"].append({"name": "Inspect test", "nodes": [rospy.get_name()]})
    path = tmp_path_factory.mktemp("inspect") / "cell.yaml"
    path.write_text(yaml.safe_dump(doc))
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


@pytest.fixture
def rate_topic(inspect: None) -> Iterator[str]:
    """This test's node publishes /inspect_test/rate (geometry_msgs/PointStamped) at 50 Hz."""
    from geometry_msgs.msg import PointStamped
    topic = f"/{TAG}/rate"
    pub = rospy.Publisher(topic, PointStamped, queue_size=10)
    stop = threading.Event()

    def run() -> None:
        rate, i = rospy.Rate(50), 0
        while not stop.is_set() and not rospy.is_shutdown():
            i += 1
            m = PointStamped()
            m.header.frame_id, m.point.x = "base", float(i)
            pub.publish(m)
            rate.sleep()

    t = threading.Thread(target=run, daemon=True)
    t.start()
    try:
        yield topic
    finally:
        stop.set()
        t.join(2)
        pub.unregister()


def test_the_graph_lists_this_topic_and_node_with_its_module(rate_topic: str) -> None:
    from cell_msgs.srv import GetRosGraph
    graph = rospy.ServiceProxy("/cell/inspect/graph", GetRosGraph)
    me = rospy.get_name()
    wait_for(lambda: any(t.name == rate_topic for t in graph().topics), 10, what="the topic in the graph")
    r = graph()
    [t] = [t for t in r.topics if t.name == rate_topic]
    assert t.type == "geometry_msgs/PointStamped" and me in t.publishers
    [n] = [n for n in r.nodes if n.name == me]
    assert n.alive and n.module == "Inspect test" and rate_topic in n.publications
    assert [x.name for x in r.topics] == sorted(x.name for x in r.topics)
    [insp] = [n for n in r.nodes if n.name == f"/{TAG}"]
    assert "/cell/inspect/graph" in insp.services and "/rosout_agg" in insp.subscriptions


def test_a_topic_measures_its_rate_and_echoes_its_last_message_while_asked(rate_topic: str) -> None:
    from cell_msgs.srv import GetRosGraph, TopicEcho, TopicStats
    stats = rospy.ServiceProxy("/cell/inspect/topic_stats", TopicStats)
    echo = rospy.ServiceProxy("/cell/inspect/echo", TopicEcho)
    assert stats(topic=rate_topic).ok
    wait_for(lambda: stats(topic=rate_topic).window_s >= 4, 10, what="4 s of measuring")
    s = stats(topic=rate_topic)
    assert s.type == "geometry_msgs/PointStamped" and s.messages >= 150
    assert abs(s.rate_hz - 50) < 5, s
    assert s.mean_bytes > 40 and abs(s.bandwidth_bps - s.rate_hz * s.mean_bytes) < 0.15 * s.bandwidth_bps
    assert 0 <= s.last_age_s < 1
    e = echo(topic=rate_topic)
    assert e.ok and e.type == "geometry_msgs/PointStamped" and 0 <= e.age_s < 1
    tree = json.loads(e.json)
    assert tree["header"]["frame_id"] == "base" and tree["point"]["x"] > 0 and tree["point"]["y"] == 0
    # A topic the inspect node itself reads typed (rospy shares the subscription): measured and echoed all the same.
    wait_for(lambda: stats(topic="/rosout_agg").messages > 0 or rospy.loginfo("inspect test: tick") or False, 10,
             what="/rosout_agg measured")
    assert stats(topic="/rosout_agg").type == "rosgraph_msgs/Log" and stats(topic="/rosout_agg").mean_bytes > 0
    agg = echo(topic="/rosout_agg")
    assert agg.ok and "msg" in json.loads(agg.json), agg.message
    bad = stats(topic="not a topic")
    assert not bad.ok and "is not a global topic name" in bad.message
    quiet = echo(topic=f"/{TAG}/nobody")
    assert not quiet.ok and "no message" in quiet.message and quiet.age_s == -1
    # Nobody asks any more: the inspect node leaves the topic (10 s after the last request).
    graph = rospy.ServiceProxy("/cell/inspect/graph", GetRosGraph)
    t0 = time.monotonic()
    wait_for(lambda: f"/{TAG}" not in next(t for t in graph().topics if t.name == rate_topic).subscribers, 20,
             what="the inspect node leaving the topic")
    assert time.monotonic() - t0 > 5


def test_a_bad_section_stops_the_node_naming_the_field(roscore: str, tmp_path: Path) -> None:
    doc = yaml.safe_load((ROOT / "config" / "demo-cell.yaml").read_text())
    doc["inspect"] = {"log_keep_s": 0}
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(doc))
    out = subprocess.run(["rosrun", "cell_nodes", "inspect_node", f"_cell_config:={path}", "__name:=inspect_bad"],
                         capture_output=True, text=True, timeout=30)
    assert out.returncode == 2, (out.stdout, out.stderr)
    assert "inspect.log_keep_s: expected a number from 1 to 86400, got 0" in out.stdout + out.stderr
