"""End to end through the WebSocket server with roslibpy (a real rosbridge client) and raw frames."""
from __future__ import annotations

import io
import struct
import threading
import time
from typing import Any, List

import cbor2
import pytest
import roslibpy
import rospy
import std_msgs.msg as std
import std_srvs.srv as std_srvs
import geometry_msgs.msg as geo

from cell_rosbridge import encoding
from rb_helpers import BridgeProcess, node_services, node_subscriptions, subscribers_of, wait_for
from rb_wsclient import WSClient


def test_publish_and_subscribe_roundtrip(ros_node: str, bridge: BridgeProcess, ros_client: Any) -> None:
    a, b = ros_client(), ros_client()
    got: List[Any] = []
    listener = roslibpy.Topic(b, "/rt_chatter", "std_msgs/String")
    listener.subscribe(got.append)
    talker = roslibpy.Topic(a, "/rt_chatter", "std_msgs/String")
    talker.advertise()
    wait_for(lambda: "/rt_chatter" in node_subscriptions(bridge.name), 5, what="bridge subscription")
    # publish until the freshly made TCPROS link delivers (ROS drops messages sent before it exists)
    wait_for(lambda: talker.publish(roslibpy.Message({"data": "hello"})) or got, 10, what="roundtrip")
    assert got[0] == {"data": "hello"}


def test_latched_operation_mode_reaches_every_late_subscriber(ros_node: str, bridge: BridgeProcess,
                                                             ros_client: Any) -> None:
    from cell_msgs.msg import OperationMode
    pub = rospy.Publisher("/rt_operation_mode", OperationMode, queue_size=1, latch=True)
    pub.publish(OperationMode(mode="running", source="test", stamp=rospy.Time(12, 34)))
    seen: List[List[Any]] = []
    for i in range(3):  # each client joins after the message was published; all must get it
        box: List[Any] = []
        seen.append(box)
        topic = roslibpy.Topic(ros_client(), "/rt_operation_mode", "cell_msgs/OperationMode")
        topic.subscribe(box.append)
        wait_for(lambda: box, 10, what=f"latched message at client {i}")
    for box in seen:
        assert box[0] == {"mode": "running", "source": "test", "stamp": {"secs": 12, "nsecs": 34}}
    # a second subscription (another component) of an already subscribed client sees it too
    extra: List[Any] = []
    second = roslibpy.Topic(ros_client(), "/rt_operation_mode", "cell_msgs/OperationMode")
    second.subscribe(lambda m: None)
    other = roslibpy.Topic(second.ros, "/rt_operation_mode", "cell_msgs/OperationMode")
    other.subscribe(extra.append)
    wait_for(lambda: extra, 10, what="latched message to second subscription")
    pub.unregister()


def test_many_subscriptions_share_one_ros_subscriber(ros_node: str, bridge: BridgeProcess,
                                                     ros_client: Any) -> None:
    pub = rospy.Publisher("/rt_shared", std.Int32, queue_size=100)
    boxes: List[List[Any]] = []
    topics = []
    for _ in range(3):
        ros = ros_client()
        for _ in range(2):
            box: List[Any] = []
            t = roslibpy.Topic(ros, "/rt_shared", "std_msgs/Int32")
            t.subscribe(box.append)
            boxes.append(box)
            topics.append(t)
    # subscribe has no acknowledgement: publish a marker until every subscription has seen one
    wait_for(lambda: pub.publish(std.Int32(data=-1)) or all(boxes), 10, what="all subscriptions live")
    for i in range(20):
        pub.publish(std.Int32(data=i))
    # per client one delivery per message (publish carries no id); roslibpy fans out per Topic object
    data = lambda box: [m["data"] for m in box if m["data"] >= 0]  # noqa: E731
    wait_for(lambda: all(len(data(b)) >= 20 for b in boxes), 10, what="all messages at all subscriptions")
    assert all(data(b) == list(range(20)) for b in boxes)
    assert pub.get_num_connections() == 1
    for t in topics:
        t.unsubscribe()
    wait_for(lambda: "/rt_shared" not in node_subscriptions(bridge.name), 10, what="released subscriber")
    pub.unregister()


def test_unsubscribe_by_id_and_without_id(ros_node: str, bridge: BridgeProcess) -> None:
    pub = rospy.Publisher("/rt_unsub", std.Int32, queue_size=10, latch=True)
    pub.publish(std.Int32(data=1))
    c = WSClient(bridge.port)
    c.send_json({"op": "subscribe", "id": "one", "topic": "/rt_unsub", "type": "std_msgs/Int32"})
    c.send_json({"op": "subscribe", "id": "two", "topic": "/rt_unsub"})
    c.recv_until(lambda m: m.get("topic") == "/rt_unsub")
    c.send_json({"op": "unsubscribe", "id": "one", "topic": "/rt_unsub"})
    c.send_json({"op": "set_level", "level": "warning"})
    c.send_json({"op": "unsubscribe", "id": "one", "topic": "/rt_unsub"})  # already gone -> warning
    warn = c.recv_until(lambda m: m["op"] == "status")
    assert warn["level"] == "warning" and warn["id"] == "one"
    assert "/rt_unsub" in node_subscriptions(bridge.name)
    pub.publish(std.Int32(data=2))
    assert c.recv_until(lambda m: m.get("topic") == "/rt_unsub")["msg"] == {"data": 2}
    c.send_json({"op": "subscribe", "id": "three", "topic": "/rt_unsub"})
    c.send_json({"op": "unsubscribe", "topic": "/rt_unsub"})  # no id: all of them
    wait_for(lambda: "/rt_unsub" not in node_subscriptions(bridge.name), 10, what="all unsubscribed")
    c.close()
    pub.unregister()


def test_rosapi_basics(ros_node: str, bridge: BridgeProcess, ros_client: Any) -> None:
    ros = ros_client()
    pub = rospy.Publisher("/rt_api_topic", std.Float32, queue_size=1)
    assert "/rt_api_topic" in ros.get_topics()
    assert ros.get_topic_type("/rt_api_topic") == "std_msgs/Float32"
    assert "/rt_api_topic" in ros.get_topics_for_type("std_msgs/Float32")
    assert "/" + bridge.name in ros.get_nodes()
    assert "/rosapi/get_time" in ros.get_services()
    assert ros.get_service_type("/rosapi/get_time") == "rosapi/GetTime"
    details = ros.get_node_details(ros_node)
    assert "/rt_api_topic" in details["publishing"]
    publishers = roslibpy.Service(ros, "/rosapi/publishers", "rosapi/Publishers")
    assert ros_node in publishers.call(roslibpy.ServiceRequest({"topic": "/rt_api_topic"}), timeout=5)["publishers"]
    typedefs = ros.get_message_details("geometry_msgs/PoseStamped")["typedefs"]
    assert typedefs[0]["type"] == "geometry_msgs/PoseStamped"
    assert {t["type"] for t in typedefs} >= {"std_msgs/Header", "geometry_msgs/Pose", "geometry_msgs/Point"}
    req = ros.get_service_request_details("std_srvs/SetBool")["typedefs"]
    assert req[0]["fieldnames"] == ["data"] and req[0]["fieldtypes"] == ["bool"]
    resp = ros.get_service_response_details("std_srvs/SetBool")["typedefs"]
    assert resp[0]["fieldnames"] == ["success", "message"]
    param = roslibpy.Param(ros, "/rt_param")
    param.set({"speed": 0.5, "names": ["a", "b"]})
    assert param.get() == {"speed": 0.5, "names": ["a", "b"]}
    assert "/rt_param/speed" in ros.get_params()
    param.delete()
    assert "/rt_param/speed" not in ros.get_params()
    assert ros.get_time()["secs"] > 0
    pub.unregister()


def test_missing_service_fails_fast_with_result_false(bridge: BridgeProcess) -> None:
    c = WSClient(bridge.port)
    start = time.monotonic()
    c.send_json({"op": "call_service", "id": "m1", "service": "/rt_no_such_service"})
    resp = c.recv_until(lambda m: m["op"] == "service_response")
    assert time.monotonic() - start < 3
    assert resp["result"] is False and resp["id"] == "m1" and "does not exist" in resp["values"]
    c.close()


def test_call_service_args_list_object_timeout_cbor(ros_node: str, bridge: BridgeProcess) -> None:
    release = threading.Event()

    def slow(req: Any) -> Any:
        release.wait(10)
        return std_srvs.TriggerResponse(success=True, message="late")

    s1 = rospy.Service("/rt_set_bool", std_srvs.SetBool, lambda r: std_srvs.SetBoolResponse(r.data, "ok"))
    s2 = rospy.Service("/rt_slow", std_srvs.Trigger, slow)
    c = WSClient(bridge.port)
    c.send_json({"op": "call_service", "id": 1, "service": "/rt_set_bool", "args": [True]})
    assert c.recv_until(lambda m: m.get("id") == 1)["values"] == {"success": True, "message": "ok"}
    c.send_json({"op": "call_service", "id": 2, "service": "/rt_set_bool", "args": {"data": False}})
    assert c.recv_until(lambda m: m.get("id") == 2)["values"]["success"] is False
    c.send_json({"op": "call_service", "id": 3, "service": "/rt_set_bool", "args": {"data": "x"}})
    bad = c.recv_until(lambda m: m.get("id") == 3)
    assert bad["result"] is False and "data" in bad["values"]
    start = time.monotonic()
    c.send_json({"op": "call_service", "id": 4, "service": "/rt_slow", "timeout": 0.3})
    late = c.recv_until(lambda m: m.get("id") == 4)
    assert late["result"] is False and "timed out" in late["values"] and time.monotonic() - start < 3
    release.set()
    c.send_json({"op": "call_service", "id": 5, "service": "/rt_set_bool", "args": [True], "compression": "cbor"})
    opcode, payload = c.recv_frame()
    assert opcode == 2 and cbor2.loads(payload)["values"]["success"] is True
    c.send_json({"op": "call_service", "id": 6, "service": "/rt_set_bool", "args": [True], "fragment_size": 20})
    frags = [c.recv() for _ in range(3)]
    assert all(f["op"] == "fragment" for f in frags)
    c.close()
    s1.shutdown()
    s2.shutdown()


def test_client_served_service(ros_node: str, bridge: BridgeProcess, ros_client: Any) -> None:
    ros = ros_client()
    service = roslibpy.Service(ros, "/rt_browser_service", "std_srvs/SetBool")

    def handler(request: Any, response: Any) -> bool:
        response["success"] = request["data"]
        response["message"] = "from browser"
        return True

    service.advertise(handler)
    wait_for(lambda: "/rt_browser_service" in node_services(bridge.name), 10, what="advertised service")
    rospy.wait_for_service("/rt_browser_service", 5)
    proxy = rospy.ServiceProxy("/rt_browser_service", std_srvs.SetBool)
    resp = proxy(True)
    assert resp.success is True and resp.message == "from browser"
    # another rosbridge client can call it through the bridge too
    other = roslibpy.Service(ros_client(), "/rt_browser_service", "std_srvs/SetBool")
    assert other.call(roslibpy.ServiceRequest({"data": False}), timeout=5)["message"] == "from browser"
    service.unadvertise()
    wait_for(lambda: "/rt_browser_service" not in node_services(bridge.name), 10, what="unadvertised")


def test_client_served_service_released_on_disconnect_and_pending_call_fails(ros_node: str,
                                                                              bridge: BridgeProcess) -> None:
    c = WSClient(bridge.port)
    c.send_json({"op": "advertise_service", "service": "/rt_gone", "type": "std_srvs/Trigger"})
    rospy.wait_for_service("/rt_gone", 5)
    result: List[Any] = []

    def call() -> None:
        try:
            rospy.ServiceProxy("/rt_gone", std_srvs.Trigger)()
            result.append("answered")
        except rospy.ServiceException as exc:
            result.append(exc)

    t = threading.Thread(target=call)
    t.start()
    request = c.recv_until(lambda m: m["op"] == "call_service")
    assert request["service"] == "/rt_gone" and request["args"] == {}
    c.close()  # never answers: the ROS caller must fail, not hang
    t.join(10)
    assert result and isinstance(result[0], rospy.ServiceException)
    wait_for(lambda: "/rt_gone" not in node_services(bridge.name), 10, what="service released")


def test_service_response_values_go_back_to_ros(ros_node: str, bridge: BridgeProcess) -> None:
    c = WSClient(bridge.port)
    c.send_json({"op": "advertise_service", "service": "/rt_answer", "type": "std_srvs/Trigger"})
    rospy.wait_for_service("/rt_answer", 5)
    out: List[Any] = []
    t = threading.Thread(target=lambda: out.append(rospy.ServiceProxy("/rt_answer", std_srvs.Trigger)()))
    t.start()
    req = c.recv_until(lambda m: m["op"] == "call_service")
    c.send_json({"op": "service_response", "id": req["id"], "service": "/rt_answer",
                 "values": {"success": True, "message": "done"}, "result": True})
    t.join(10)
    assert out[0].success is True and out[0].message == "done"
    c.send_json({"op": "unadvertise_service", "service": "/rt_answer"})
    wait_for(lambda: "/rt_answer" not in node_services(bridge.name), 10, what="unadvertised")
    c.close()


def test_cbor_cbor_raw_png_and_fragments_on_subscribe(ros_node: str, bridge: BridgeProcess) -> None:
    pub = rospy.Publisher("/rt_multi", std.Float64MultiArray, queue_size=10, latch=True)
    msg = std.Float64MultiArray(data=[1.0, float("nan"), 3.5])
    pub.publish(msg)
    clients = {}
    for comp in ("cbor", "cbor-raw", "png", "none"):
        c = WSClient(bridge.port)
        c.send_json({"op": "subscribe", "topic": "/rt_multi", "type": "std_msgs/Float64MultiArray",
                     "compression": comp, "fragment_size": 40 if comp == "none" else 0})
        clients[comp] = c
    opcode, payload = clients["cbor"].recv_frame()
    assert opcode == 2
    decoded = cbor2.loads(payload)
    assert decoded["op"] == "publish" and decoded["topic"] == "/rt_multi"
    values = struct.unpack("<3d", decoded["msg"]["data"].value)
    assert values[0] == 1.0 and values[1] != values[1] and values[2] == 3.5
    opcode, payload = clients["cbor-raw"].recv_frame()
    raw = cbor2.loads(payload)["msg"]
    assert set(raw) == {"secs", "nsecs", "bytes"}
    back = std.Float64MultiArray()
    back.deserialize(raw["bytes"])
    assert back.data[2] == 3.5
    png = clients["png"].recv()
    assert png["op"] == "png"
    assert encoding.png_decode(png["data"]).startswith('{"op":"publish","topic":"/rt_multi"')
    first = clients["none"].recv()
    assert first["op"] == "fragment" and first["num"] == 0
    parts = [first] + [clients["none"].recv() for _ in range(first["total"] - 1)]
    import json
    whole = json.loads("".join(p["data"] for p in sorted(parts, key=lambda p: p["num"])))
    assert whole["msg"]["data"] == [1.0, None, 3.5]
    for c in clients.values():
        c.close()
    pub.unregister()


def test_cbor_request_and_header_filled_on_publish(ros_node: str, bridge: BridgeProcess) -> None:
    got: List[Any] = []
    sub = rospy.Subscriber("/rt_pose", geo.PoseStamped, got.append)
    c = WSClient(bridge.port)
    c.send_cbor({"op": "advertise", "topic": "/rt_pose", "type": "geometry_msgs/PoseStamped"})
    wait_for(lambda: sub.get_num_connections() > 0, 10, what="bridge publisher connected")
    before = rospy.Time.now()
    c.send_cbor({"op": "publish", "topic": "/rt_pose", "msg": {"pose": {"position": {"x": 1.0}}}})
    c.send_json({"op": "publish", "topic": "/rt_pose", "msg": {"header": {"frame_id": "base"}}})
    wait_for(lambda: len(got) >= 2, 10, what="published poses")
    assert got[0].pose.position.x == 1.0
    assert got[0].header.stamp >= before and got[0].header.frame_id == ""
    assert got[1].header.frame_id == "base" and got[1].header.stamp >= before
    assert got[1].header.seq == got[0].header.seq + 1
    c.close()
    sub.unregister()


def test_throttle_and_queue_apply_per_client(ros_node: str, bridge: BridgeProcess) -> None:
    pub = rospy.Publisher("/rt_rate", std.Int32, queue_size=100)
    fast = WSClient(bridge.port)
    slow = WSClient(bridge.port)
    fast.send_json({"op": "subscribe", "id": "f", "topic": "/rt_rate", "type": "std_msgs/Int32"})
    slow.send_json({"op": "subscribe", "id": "s", "topic": "/rt_rate", "type": "std_msgs/Int32",
                    "throttle_rate": 300, "queue_length": 1})
    wait_for(lambda: pub.get_num_connections() == 1, 10, what="bridge connected")
    start = time.monotonic()
    for i in range(30):
        pub.publish(std.Int32(data=i))
        time.sleep(0.01)  # a 100 Hz source, not a wait for a condition
    fast_got = [fast.recv_until(lambda m: m.get("op") == "publish")["msg"]["data"] for _ in range(30)]
    assert fast_got == list(range(30))
    slow_got = []
    deadline = time.monotonic() + 3
    while time.monotonic() < deadline and (not slow_got or slow_got[-1] != 29):
        slow_got.append(slow.recv_until(lambda m: m.get("op") == "publish")["msg"]["data"])
    elapsed = time.monotonic() - start
    assert slow_got[-1] == 29, slow_got  # the newest is delivered, never lost
    assert len(slow_got) <= int(elapsed / 0.3) + 2, (slow_got, elapsed)
    fast.close()
    slow.close()
    pub.unregister()


def test_status_error_does_not_disturb_other_clients(ros_node: str, bridge: BridgeProcess) -> None:
    pub = rospy.Publisher("/rt_calm", std.Int32, queue_size=10, latch=True)
    pub.publish(std.Int32(data=7))
    good, bad = WSClient(bridge.port), WSClient(bridge.port)
    bad.send_text("{{{{")
    assert bad.recv()["op"] == "status"
    bad.send_json({"op": "publish", "id": "x", "topic": "/rt_calm", "msg": {"data": "seven"}})
    status = bad.recv_until(lambda m: m["op"] == "status")
    assert status["id"] == "x" and "data" in status["msg"]
    good.send_json({"op": "subscribe", "topic": "/rt_calm"})
    assert good.recv_until(lambda m: m.get("op") == "publish")["msg"] == {"data": 7}
    bad.send_json({"op": "subscribe", "topic": "/rt_calm"})  # and the bad one still works
    assert bad.recv_until(lambda m: m.get("op") == "publish")["msg"] == {"data": 7}
    good.close()
    bad.close()
    pub.unregister()


def test_listens_on_loopback_only(bridge: BridgeProcess) -> None:
    port_hex = f"{bridge.port:04X}"
    listening = []
    for path in ("/proc/net/tcp", "/proc/net/tcp6"):
        with open(path) as f:
            for line in f.readlines()[1:]:
                local, state = line.split()[1], line.split()[3]
                if state == "0A" and local.endswith(":" + port_hex):
                    listening.append(local)
    assert listening == ["0100007F:" + port_hex]


def test_client_cannot_hijack_existing_services(ros_node: str, bridge: BridgeProcess) -> None:
    a, b = WSClient(bridge.port), WSClient(bridge.port)
    a.send_json({"op": "advertise_service", "id": "h", "service": "/rosapi/get_time", "type": "rosapi/GetTime"})
    status = a.recv_until(lambda m: m["op"] == "status")
    assert status["id"] == "h" and "already provided by /rosapi" in status["msg"]
    a.send_json({"op": "advertise_service", "service": "/rt_owned", "type": "std_srvs/Trigger"})
    rospy.wait_for_service("/rt_owned", 5)
    b.send_json({"op": "advertise_service", "id": "h2", "service": "/rt_owned", "type": "std_srvs/Trigger"})
    assert "another client" in b.recv_until(lambda m: m["op"] == "status")["msg"]
    b.send_json({"op": "call_service", "id": "t", "service": "/rosapi/get_time"})
    assert b.recv_until(lambda m: m.get("id") == "t")["result"] is True
    a.close()
    b.close()
