"""The Inspect page's topics and nodes without ROS (cell_nodes.inspect.graph, .topics): the graph from the master's
answers, the measured rate and bandwidth, watches that end when nobody asks, and a message as a readable tree."""
from __future__ import annotations

import json
import math

import pytest
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import Image, JointState

from cell_nodes.inspect.graph import build_graph, modules_by_node, registered_nodes
from cell_nodes.inspect.topics import (IDLE_S, MAX_ITEMS, MAX_STRING, TopicWatch, WatchRefused, Watches, to_tree,
                                       topic_name_problem)
from cell_nodes.modules.config import parse_modules

STATE = [
    [["/joint_states", ["/manual"]], ["/rosout", ["/manual", "/vision"]]],
    [["/joint_states", ["/recorder", "/rosbridge"]], ["/cell/vision/brightness", ["/vision_monitor"]]],
    [["/cell/manual/stop", ["/manual"]], ["/vision/get_loggers", ["/vision"]]],
]
TYPES = [["/joint_states", "sensor_msgs/JointState"], ["/rosout", "rosgraph_msgs/Log"]]


def test_the_graph_lists_topics_with_type_publishers_and_subscribers_and_nodes_with_their_module() -> None:
    modules = parse_modules([{"name": "Vision", "nodes": ["/vision", "vision_monitor"]},
                             {"name": "Other", "nodes": ["/vision"]}])
    topics, nodes = build_graph(STATE, TYPES, alive={"/manual", "/vision"}, module_of=modules_by_node(modules))
    assert [t.name for t in topics] == ["/cell/vision/brightness", "/joint_states", "/rosout"]
    js = topics[1]
    assert (js.type, js.publishers, js.subscribers) == ("sensor_msgs/JointState", ("/manual",), ("/recorder", "/rosbridge"))
    assert topics[0].type == "" and topics[0].publishers == ()   # only subscribed, no type known
    by = {n.name: n for n in nodes}
    assert [n.name for n in nodes] == registered_nodes(STATE) == sorted(by)
    assert by["/manual"].publications == ["/joint_states", "/rosout"] and by["/manual"].services == ["/cell/manual/stop"]
    assert by["/vision"].module == "Vision" and by["/vision_monitor"].module == "Vision" and by["/manual"].module == ""
    assert by["/vision"].alive and not by["/vision_monitor"].alive
    assert by["/vision_monitor"].subscriptions == ["/cell/vision/brightness"]


def test_rate_and_bandwidth_over_the_window() -> None:
    w = TopicWatch("/t", started=100.0, unsubscribe=lambda: None)
    assert w.stats(100.5).last_age_s == -1 and w.stats(100.5).rate_hz == 0
    for i in range(500):                     # 50 Hz for 10 s, 200 bytes each
        w.add(101.0 + i / 50, b"x" * 200, "std_msgs/String")
    s = w.stats(101.0 + 499 / 50)
    assert s.messages == 500 and s.rate_hz == pytest.approx(50.0) and s.mean_bytes == 200
    assert s.bandwidth_bps == pytest.approx(500 * 200 / (499 / 50))
    assert s.window_s == 10.0 and w.type == "std_msgs/String"
    later = w.stats(101.0 + 499 / 50 + 6)    # the publisher stopped 6 s ago: the window keeps the last 4 s of it
    assert later.messages == pytest.approx(200, abs=1) and later.last_age_s == pytest.approx(6.0)
    assert later.bandwidth_bps == pytest.approx(later.messages * 200 / 10)   # falls as the last messages age


def test_a_watch_lives_while_asked_and_ends_idle_s_after_the_last_request() -> None:
    subscribed, stopped = [], []

    def subscribe(topic, watch):
        subscribed.append(topic)
        return lambda: stopped.append(topic)

    ws = Watches(subscribe, max_watches=2)
    a = ws.touch("/a", 0.0)
    assert ws.touch("/a", IDLE_S - 1) is a and subscribed == ["/a"]
    ws.touch("/b", IDLE_S - 1)
    with pytest.raises(WatchRefused, match="at most 2"):
        ws.touch("/c", IDLE_S)
    assert ws.expire(2 * IDLE_S - 1.5) == [] and stopped == []
    assert sorted(ws.expire(2 * IDLE_S)) == ["/a", "/b"] and sorted(stopped) == ["/a", "/b"] and ws.topics() == []
    ws.touch("/c", 2 * IDLE_S)
    ws.close()
    assert stopped[-1] == "/c"


def test_a_message_as_a_tree_cuts_long_arrays_bytes_and_strings() -> None:
    js = JointState(name=[f"j{i}" for i in range(40)], position=[0.5] * 40, velocity=[math.nan], effort=[])
    js.header.stamp.secs, js.header.frame_id = 12, "x" * (MAX_STRING + 5)
    tree = to_tree(js)
    assert tree["header"]["stamp"] == {"secs": 12, "nsecs": 0}
    assert tree["header"]["frame_id"].endswith(f"({MAX_STRING + 5} characters)")
    assert tree["name"][:2] == ["j0", "j1"] and len(tree["name"]) == MAX_ITEMS + 1
    assert tree["name"][-1] == f"... {40 - MAX_ITEMS} more (40 items)"
    assert tree["velocity"] == ["nan"] and tree["effort"] == []
    img = Image(height=2, width=3, encoding="rgb8", data=bytes(18))
    assert to_tree(img)["data"] == "<18 bytes>"
    # A message decoded from the wire (what the node does) gives the same tree; it is valid JSON.
    pose = PoseStamped()
    pose.pose.position.x = 1.25
    from io import BytesIO
    buf = BytesIO()
    pose.serialize(buf)
    back = to_tree(PoseStamped().deserialize(buf.getvalue()))
    assert back["pose"]["position"] == {"x": 1.25, "y": 0.0, "z": 0.0}
    json.dumps(to_tree(js), allow_nan=False)


@pytest.mark.parametrize("name,ok", [("/joint_states", True), ("/cell/manual/arm/state", True), ("joint_states", False),
                                     ("/a b", False), ("/", False), ("", False), ("/1abc", False)])
def test_topic_names(name: str, ok: bool) -> None:
    assert (topic_name_problem(name) is None) == ok
