"""The dispatcher without any socket: errors, fragments, subscriptions, publishing, resource release."""
from __future__ import annotations

import json
import subprocess
import sys
from typing import Any, List

import cbor2
import pytest
import rospy
import std_msgs.msg as std

from cell_rosbridge.node import build_context
from cell_rosbridge.outbox import ClientOutbox
from cell_rosbridge.protocol import BridgeConfig, BridgeContext, Client
from rb_helpers import node_publications, node_subscriptions, wait_for


class Harness:
    def __init__(self, context: BridgeContext) -> None:
        self.closed: List[str] = []
        self.client = Client(context, ClientOutbox(context.config.max_client_buffer, 100,
                                                   wakeup=lambda: None, on_overflow=self.closed.append))
        self.received: List[Any] = []

    def send(self, obj: Any) -> None:
        self.client.incoming(json.dumps(obj) if not isinstance(obj, (str, bytes)) else obj)

    def drain(self) -> List[Any]:
        while True:
            frames, _ = self.client.outbox.pop(1e12)
            if frames is None:
                break
            for f in frames:
                self.received.append(cbor2.loads(f) if isinstance(f, bytes) else json.loads(f))
        return self.received

    def statuses(self) -> List[Any]:
        return [m for m in self.drain() if m["op"] == "status"]


@pytest.fixture
def ctx() -> BridgeContext:
    context = build_context(BridgeConfig(max_message_size=5000))
    yield context
    context.hub.shutdown()
    context.publishers.shutdown()


@pytest.fixture
def h(ctx: BridgeContext) -> Harness:
    harness = Harness(ctx)
    yield harness
    harness.client.finish()


@pytest.mark.parametrize("frame,op,mid,needle", [
    ("{not json", "unknown", None, "cannot parse JSON"),
    ('["op", "subscribe"]', "unknown", None, "must be an object"),
    ('{"id": "x1"}', "unknown", "x1", "'op'"),
    ('{"op": "teleport", "id": 7}', "teleport", 7, "unknown operation"),
    ('{"op": "subscribe", "id": "s1"}', "subscribe", "s1", "missing field 'topic'"),
    ('{"op": "subscribe", "id": "s2", "topic": 5}', "subscribe", "s2", "must be str"),
    ('{"op": "subscribe", "id": "s3", "topic": "/a", "throttle_rate": "fast"}', "subscribe", "s3", "throttle_rate"),
    ('{"op": "subscribe", "id": "s4", "topic": "/a", "compression": "zip"}', "subscribe", "s4", "compression"),
    ('{"op": "advertise", "id": "a1", "topic": "/a", "type": "nope/Nope"}', "advertise", "a1", "unknown message type"),
    ('{"op": "publish", "id": "p1", "topic": "/never_existed_xyz", "msg": {}}', "publish", "p1", "does not exist"),
    ('{"op": "publish", "id": "p2", "topic": "/a", "msg": 3}', "publish", "p2", "'msg' must be dict"),
    ('{"op": "call_service", "id": "c1", "service": "/x", "args": 3}', "call_service", "c1", "args"),
    ('{"op": "service_response", "id": "r1", "service": "/nobody"}', "service_response", "r1", "not advertised"),
    ('{"op": "fragment", "id": "f", "data": "x", "num": 3, "total": 2}', "fragment", "f", "numbering"),
])
def test_bad_requests_get_a_status_error_naming_op_and_id(ros_node: str, h: Harness, frame: str, op: str,
                                                        mid: Any, needle: str) -> None:
    h.send(frame)
    [status] = h.statuses()
    assert status["level"] == "error"
    assert status["msg"].startswith(op + ":"), status
    assert needle in status["msg"], status
    assert status.get("id") == mid


def test_oversized_frame_reports_op_and_id_and_connection_continues(ros_node: str, h: Harness) -> None:
    big = json.dumps({"op": "publish", "id": "big1", "topic": "/a", "msg": {"data": "x" * 6000}})
    h.send(big)
    [status] = h.statuses()
    assert status["id"] == "big1" and status["msg"].startswith("publish:") and "max_message_size" in status["msg"]
    h.send({"op": "nope", "id": "after"})
    assert h.statuses()[-1]["id"] == "after"


def test_message_not_matching_type_is_rejected_and_not_published(ros_node: str, h: Harness) -> None:
    h.send({"op": "advertise", "topic": "/proto_typed", "type": "std_msgs/Int8"})
    h.send({"op": "publish", "id": "m1", "topic": "/proto_typed", "msg": {"data": 1000}})
    [status] = h.statuses()
    assert status["id"] == "m1" and "out of range" in status["msg"]
    h.send({"op": "advertise", "id": "a2", "topic": "/proto_typed", "type": "std_msgs/String"})
    assert "already has type std_msgs/Int8" in h.statuses()[-1]["msg"]


def test_set_level_controls_warnings(ros_node: str, h: Harness) -> None:
    h.send({"op": "unadvertise", "topic": "/not_mine"})
    assert h.statuses() == []  # warning filtered at the default level (error)
    h.send({"op": "set_level", "level": "warning"})
    h.send({"op": "unadvertise", "id": "u", "topic": "/not_mine"})
    assert h.statuses()[-1]["level"] == "warning"
    h.send({"op": "set_level", "level": "none"})
    h.send({"op": "nope"})
    assert len(h.statuses()) == 1
    h.send({"op": "set_level", "level": "loud"})  # spec: dropped
    h.send({"op": "nope"})
    assert len(h.statuses()) == 1


def test_incoming_fragments_are_reassembled_in_any_order(ros_node: str, h: Harness) -> None:
    text = json.dumps({"op": "nope_from_fragments", "id": "frag-op", "pad": "z" * 300})
    parts = [text[i:i + 50] for i in range(0, len(text), 50)]
    order = list(range(len(parts)))[::-1]
    for n in order:
        h.send({"op": "fragment", "id": "F1", "data": parts[n], "num": n, "total": len(parts)})
    [status] = h.statuses()
    assert status["id"] == "frag-op" and "nope_from_fragments" in status["msg"]
    assert h.client.fragments == {}


def test_fragment_reassembly_is_bounded(ros_node: str, h: Harness) -> None:
    for n in range(200):  # 200 * 40 chars > max_message_size 5000
        h.send({"op": "fragment", "id": "huge", "data": "x" * 40, "num": n, "total": 1000})
    assert any("exceeds max_message_size" in s["msg"] for s in h.statuses())
    assert all(buf["size"] <= 5000 for buf in h.client.fragments.values())
    for n in range(40):  # many half-sent ids: only max_fragment_buffers are kept
        h.send({"op": "fragment", "id": f"id{n}", "data": "x", "num": 0, "total": 2})
    assert len(h.client.fragments) == h.client.context.config.max_fragment_buffers


def test_cbor_request_is_accepted(ros_node: str, h: Harness) -> None:
    h.send(cbor2.dumps({"op": "teleport", "id": "cb"}))
    [status] = h.statuses()
    assert status["id"] == "cb" and "unknown operation" in status["msg"]


def test_subscribe_needs_type_for_unknown_topic(ros_node: str, h: Harness) -> None:
    h.send({"op": "subscribe", "id": "s", "topic": "/proto_never_seen"})
    [status] = h.statuses()
    assert "cannot infer the type" in status["msg"]


def test_shared_subscriber_and_release(ros_node: str, ctx: BridgeContext) -> None:
    a, b = Harness(ctx), Harness(ctx)
    pub = rospy.Publisher("/proto_shared", std.String, queue_size=10, latch=True)
    pub.publish(std.String(data="state"))
    a.send({"op": "subscribe", "id": "1", "topic": "/proto_shared", "type": "std_msgs/String"})
    a.send({"op": "subscribe", "id": "2", "topic": "/proto_shared", "throttle_rate": 10})
    b.send({"op": "subscribe", "id": "1", "topic": "/proto_shared"})
    assert ctx.hub.count() == 1
    wait_for(lambda: any(m.get("topic") == "/proto_shared" for m in a.drain()), 5, what="latched to a")
    wait_for(lambda: any(m.get("topic") == "/proto_shared" for m in b.drain()), 5, what="latched to b")
    assert a.statuses() == [] and b.statuses() == []
    a.send({"op": "unsubscribe", "id": "1", "topic": "/proto_shared"})
    assert "/proto_shared" in a.client.subscriptions
    a.client.finish()
    assert ctx.hub.count() == 1
    b.send({"op": "unsubscribe", "topic": "/proto_shared"})
    assert ctx.hub.count() == 0
    pub.unregister()


def test_a_late_subscriber_gets_the_latched_message_of_every_publisher(ros_node: str, ctx: BridgeContext) -> None:
    # /tf_static is the case: several nodes latch their own frames on one topic, and ROS gives a new subscriber all.
    script = ("import sys, rospy, std_msgs.msg as m; rospy.init_node('proto_other_latcher');"
              "p = rospy.Publisher('/proto_two_latched', m.String, queue_size=1, latch=True);"
              "p.publish(m.String(data='from the other node')); sys.stdin.read()")
    other = subprocess.Popen([sys.executable, "-c", script], stdin=subprocess.PIPE)
    try:
        pub = rospy.Publisher("/proto_two_latched", std.String, queue_size=1, latch=True)
        pub.publish(std.String(data="from this node"))
        first = Harness(ctx)
        first.send({"op": "subscribe", "topic": "/proto_two_latched", "type": "std_msgs/String"})
        both = {"from this node", "from the other node"}
        wait_for(lambda: {m["msg"]["data"] for m in first.drain() if m.get("op") == "publish"} == both, 15,
                 what="both latched messages to the first subscriber")
        late = Harness(ctx)  # joins the shared subscription: the bridge replays what it has
        late.send({"op": "subscribe", "topic": "/proto_two_latched", "type": "std_msgs/String"})
        assert {m["msg"]["data"] for m in late.drain() if m.get("op") == "publish"} == both
        first.client.finish()
        late.client.finish()
        pub.unregister()
    finally:
        other.kill()
        other.wait()


def test_publish_fills_defaults_with_warning_and_finish_releases_publisher(ros_node: str, h: Harness,
                                                                          ctx: BridgeContext) -> None:
    got: List[Any] = []
    sub = rospy.Subscriber("/proto_pub", std.ColorRGBA, got.append)
    h.send({"op": "set_level", "level": "warning"})
    h.send({"op": "advertise", "topic": "/proto_pub", "type": "std_msgs/ColorRGBA"})
    pub = ctx.publishers.get("/proto_pub")
    wait_for(lambda: pub.pub.get_num_connections() > 0, 5, what="publisher connection")
    h.send({"op": "publish", "id": "p", "topic": "/proto_pub", "msg": {"r": 0.5}})
    wait_for(lambda: got, 5, what="published message")
    assert got[0].r == 0.5 and got[0].g == 0.0
    assert "fields defaulted: g, b, a" in h.statuses()[-1]["msg"]
    h.client.finish()
    assert ctx.publishers.count() == 0
    sub.unregister()


def test_each_message_is_encoded_once_for_all_clients(ros_node: str, ctx: BridgeContext, monkeypatch: Any) -> None:
    from cell_rosbridge import conversion
    calls: List[bool] = []
    real = conversion.msg_to_dict

    def counting(msg: Any, cbor: bool = False) -> Any:
        # top level only (the walker recurses), and only the measured message (warm-ups may trail)
        if isinstance(msg, std.Float64MultiArray) and list(msg.data) == [2.0]:
            calls.append(cbor)
        return real(msg, cbor)

    monkeypatch.setattr(conversion, "msg_to_dict", counting)
    clients = [Harness(ctx) for _ in range(5)]
    pub = rospy.Publisher("/proto_once", std.Float64MultiArray, queue_size=10)
    for i, c in enumerate(clients):
        c.send({"op": "subscribe", "topic": "/proto_once", "type": "std_msgs/Float64MultiArray",
                "compression": "cbor" if i == 4 else "none"})
    wait_for(lambda: pub.get_num_connections() == 1, 10, what="bridge subscribed")
    wait_for(lambda: pub.publish(std.Float64MultiArray(data=[1.0])) or all(
        any(m.get("op") == "publish" for m in c.drain()) for c in clients), 10, what="all clients got one")
    calls.clear()
    for c in clients:
        c.received.clear()
    pub.publish(std.Float64MultiArray(data=[2.0]))
    wait_for(lambda: all(any(m.get("op") == "publish" and _data(m) == [2.0] for m in c.drain())
                         for c in clients), 10, what="second message everywhere")
    assert sorted(calls) == [False, True]  # one JSON conversion and one CBOR conversion, for 5 clients
    for c in clients:
        c.client.finish()
    pub.unregister()


def _data(m: Any) -> Any:
    data = m["msg"]["data"]
    if hasattr(data, "value"):  # CBOR typed array
        import struct
        return list(struct.unpack(f"<{len(data.value) // 8}d", data.value))
    return data


def test_subscribe_with_wrong_type_for_existing_topic(ros_node: str, h: Harness) -> None:
    pub = rospy.Publisher("/proto_typed_sub", std.String, queue_size=1)
    h.send({"op": "subscribe", "id": "w", "topic": "/proto_typed_sub", "type": "std_msgs/Int8"})
    [status] = h.statuses()
    assert status["id"] == "w" and "has type std_msgs/String" in status["msg"]
    h.send({"op": "subscribe", "id": "ok", "topic": "/proto_typed_sub"})  # inferred from the graph
    assert h.statuses() == [status]
    assert h.client.subscriptions["/proto_typed_sub"].type_name == "std_msgs/String"
    pub.unregister()


def test_dispatcher_and_capabilities_have_no_import_circle() -> None:
    """protocol.py imports no capability; a capability imports neither protocol.py nor another capability."""
    import ast
    import pathlib
    pkg = pathlib.Path(__file__).resolve().parents[1] / "src" / "cell_rosbridge"

    def imported(path: pathlib.Path) -> List[str]:
        names: List[str] = []
        for node in ast.walk(ast.parse(path.read_text())):  # late imports inside functions count too
            if isinstance(node, ast.ImportFrom):
                base = "." * node.level + (node.module or "")
                sep = "" if base.endswith(".") else "."
                names += [base] + [base + sep + a.name for a in node.names]
            elif isinstance(node, ast.Import):
                names += [a.name for a in node.names]
        return names

    assert not [n for n in imported(pkg / "protocol.py") if "capabilities" in n]
    ops = {p.stem for p in (pkg / "capabilities").glob("*.py") if p.stem != "__init__"}
    for path in (pkg / "capabilities").glob("*.py"):
        if path.stem == "__init__":
            continue
        names = imported(path)
        assert not [n for n in names if "protocol" in n], path.name
        assert not [n for n in names if n.startswith(".") and not n.startswith("..")
                    and n.lstrip(".").split(".")[0] in ops], path.name
