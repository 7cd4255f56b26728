"""The rosbridge protocol on either ROS generation, one test body each: pytest runs this file under ROS 1 (the
project venv) and under ROS 2 Jazzy (.venv-ros2, scripts/test-all.sh). Clients are roslibpy, a rosbridge client
nobody here wrote; the ROS side of each case is our server's own ROS plumbing, reached through a second client.
"""
from __future__ import annotations

import threading
import time
from typing import Any, Callable, Iterator, List

import pytest
import roslibpy

from rb_helpers import ROS_VERSION, BridgeProcess, wait_for


@pytest.fixture(scope="module")
def server(ros_graph: str) -> Iterator[BridgeProcess]:
    b = BridgeProcess(name=f"rosbridge_gen{ROS_VERSION}")
    yield b
    assert b.stop() == 0, b.log()


@pytest.fixture
def connect(server: BridgeProcess) -> Iterator[Callable[[], roslibpy.Ros]]:
    made: List[roslibpy.Ros] = []

    def make() -> roslibpy.Ros:
        ros = roslibpy.Ros("127.0.0.1", server.port)
        ros.run(timeout=10)
        made.append(ros)
        return ros

    yield make
    for ros in made:
        if ros.is_connected:
            ros.close()


class Heard(list):
    """Messages a subscription heard, and an event set by the first."""

    def __init__(self) -> None:
        super().__init__()
        self.event = threading.Event()

    __hash__ = object.__hash__  # roslibpy keys its handlers by the callable

    def __call__(self, msg: Any) -> None:
        self.append(msg)
        self.event.set()


def collect(ros: roslibpy.Ros, topic: str, type_name: str, **kw: Any) -> Heard:
    got = Heard()
    roslibpy.Topic(ros, topic, type_name, **kw).subscribe(got)
    return got


def publish_until(pub: roslibpy.Topic, msg: dict, got: Heard, what: str) -> None:
    """Publish until the subscriber hears it: a new publisher's first messages may precede the match (ROS 2's
    discovery, ROS 1's connection set-up), as for any ROS publisher."""
    deadline = time.monotonic() + 10
    while not got and time.monotonic() < deadline:
        pub.publish(roslibpy.Message(msg))
        got.event.wait(0.1)  # again after a tenth of a second unless heard
    assert got, f"no message on {what}"


@pytest.mark.parametrize("pub_type,sub_type", [("std_msgs/String", "std_msgs/msg/String"),
                                               ("std_msgs/msg/String", "std_msgs/String")])
def test_publish_and_subscribe_with_either_type_spelling(connect: Callable[[], roslibpy.Ros], pub_type: str,
                                                         sub_type: str) -> None:
    a, b = connect(), connect()
    topic = f"/gen_chat_{pub_type.count('/')}"
    got = collect(b, topic, sub_type)
    pub = roslibpy.Topic(a, topic, pub_type)
    pub.advertise()
    publish_until(pub, {"data": "hello"}, got, topic)
    assert got[0] == {"data": "hello"}


def test_a_late_subscriber_gets_the_latched_state(connect: Callable[[], roslibpy.Ros]) -> None:
    a = connect()
    pub = roslibpy.Topic(a, "/gen_mode", "cell_msgs/OperationMode", latch=True)
    pub.advertise()
    first = collect(a, "/gen_mode", "cell_msgs/OperationMode")
    publish_until(pub, {"mode": "manual", "source": "test"}, first, "/gen_mode")
    late = collect(connect(), "/gen_mode", "cell_msgs/OperationMode")  # a new client, after the publish
    wait_for(lambda: bool(late), 10, what="the latched mode")
    assert late[0]["mode"] == "manual" and late[0]["source"] == "test"
    stamp = late[0]["stamp"]  # ROS 1 time {secs, nsecs}; ROS 2 builtin_interfaces/Time {sec, nanosec}
    assert set(stamp) == ({"secs", "nsecs"} if ROS_VERSION == 1 else {"sec", "nanosec"})


def test_images_and_byte_arrays_round_trip_as_base64(connect: Callable[[], roslibpy.Ros]) -> None:
    a, b = connect(), connect()
    got = collect(b, "/gen_image", "sensor_msgs/Image")
    pub = roslibpy.Topic(a, "/gen_image", "sensor_msgs/Image")
    pub.advertise()
    publish_until(pub, {"height": 1, "width": 2, "encoding": "rgb8", "step": 6, "data": "AQIDBAUG"}, got,
                  "/gen_image")
    assert got[0]["data"] == "AQIDBAUG" and got[0]["width"] == 2
    assert got[0]["header"]["frame_id"] == ""  # the omitted header was filled (stamped now, by the spec)


def test_a_service_offered_by_one_client_is_called_by_another(connect: Callable[[], roslibpy.Ros]) -> None:
    a, b = connect(), connect()
    served = roslibpy.Service(a, "/gen_set_flag", "std_srvs/SetBool")

    def handler(request: Any, response: Any) -> bool:
        response["success"] = bool(request["data"])
        response["message"] = f"flag {request['data']}"
        return True

    served.advertise(handler)
    caller = roslibpy.Service(b, "/gen_set_flag", "std_srvs/SetBool")
    deadline = time.monotonic() + 10
    while True:  # the advertisement reaches the graph
        try:
            answer = caller.call(roslibpy.ServiceRequest({"data": True}), timeout=5)
            break
        except Exception:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.1)
    assert answer["success"] is True and answer["message"] == "flag True"


def test_a_missing_service_is_answered_with_a_failure(connect: Callable[[], roslibpy.Ros]) -> None:
    ros = connect()
    errors: List[Any] = []
    done = threading.Event()
    roslibpy.Service(ros, "/gen_nobody_serves_this", "std_srvs/Trigger").call(
        roslibpy.ServiceRequest({}), callback=lambda _r: done.set(), errback=lambda e: (errors.append(e), done.set()))
    assert done.wait(10)
    assert errors and "does not exist" in str(errors[0])


def test_bad_requests_get_a_status_error_and_the_connection_goes_on(connect: Callable[[], roslibpy.Ros],
                                                                    server: BridgeProcess) -> None:
    from rb_wsclient import WSClient
    ws = WSClient(server.port, timeout=10)
    try:
        for bad in ({"op": "subscribe", "id": "s1", "topic": "/gen_x", "type": "no_such_pkg/Nothing"},
                    {"op": "publish", "id": "p1", "topic": "/gen_chat_typed", "msg": {"data": 5}},
                    {"op": "advertise", "id": "a1", "topic": "bad topic!", "type": "std_msgs/String"}):
            if bad["op"] == "publish":
                ws.send_json({"op": "advertise", "topic": "/gen_chat_typed", "type": "std_msgs/String"})
            ws.send_json(bad)
            status = ws.recv_until(lambda m: isinstance(m, dict) and m.get("op") == "status" and m.get("id") == bad["id"], 10)
            assert status["level"] == "error", status
        got = collect(connect(), "/gen_alive", "std_msgs/String")
        pub = roslibpy.Topic(connect(), "/gen_alive", "std_msgs/String")
        pub.advertise()
        publish_until(pub, {"data": "still here"}, got, "/gen_alive")
    finally:
        ws.close()


def test_a_goal_to_a_missing_action_server_ends_with_a_clear_failure(server: BridgeProcess) -> None:
    from rb_wsclient import WSClient
    ws = WSClient(server.port, timeout=10)
    try:
        ws.send_json({"op": "send_action_goal", "id": "g1", "action": "/gen_nobody/follow_joint_trajectory",
                      "action_type": "control_msgs/action/FollowJointTrajectory", "args": {}})
        out = ws.recv_until(lambda m: isinstance(m, dict) and m.get("id") == "g1", 15)
        assert out["op"] == "action_result" and out["result"] is False and out["status"] == 0
        # ROS 2: no server under that name; ROS 1 has no action ops in rosbridge's protocol (its topics instead)
        assert ("is not available" if ROS_VERSION == 2 else "needs a ROS 2 server") in out["values"]
    finally:
        ws.close()


@pytest.fixture(scope="module")
def rosapi_node(ros_graph: str) -> Iterator[None]:
    import os
    import subprocess
    import sys
    from rb_helpers import ROSAPI
    proc = subprocess.Popen([sys.executable, str(ROSAPI)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            start_new_session=True, env=dict(os.environ))
    yield None
    proc.terminate()
    assert proc.wait(10) is not None


def test_rosapi_answers_under_its_names(connect: Callable[[], roslibpy.Ros], rosapi_node: None) -> None:
    ros = connect()
    pub = roslibpy.Topic(connect(), "/gen_api_topic", "std_msgs/String")
    pub.advertise()

    def listed() -> bool:
        try:
            return "/gen_api_topic" in ros.get_topics()
        except Exception:  # rosapi still starting: its services are not there yet
            return False

    wait_for(listed, 20, what="/gen_api_topic in /rosapi/topics")
    short = {1: "std_msgs/String", 2: "std_msgs/msg/String"}[ROS_VERSION]  # each generation's own spelling
    assert ros.get_topic_type("/gen_api_topic") == short
    assert "/rosapi/topics" in ros.get_services()
    assert ros.get_service_type("/rosapi/topics").endswith("/Topics")
    assert "/rosapi" in ros.get_nodes()
    header = {1: "std_msgs/Header", 2: "std_msgs/msg/Header"}[ROS_VERSION]
    typedefs = ros.get_message_details(header)["typedefs"]
    assert typedefs[0]["type"] == header and {"stamp", "frame_id"} <= set(typedefs[0]["fieldnames"])


def test_a_byte_field_is_a_number_on_the_wire(connect: Callable[[], roslibpy.Ros]) -> None:
    """diagnostic_msgs' `byte level`: int8 on ROS 1, an octet (one bytes object in rclpy) on ROS 2."""
    a, b = connect(), connect()
    got = collect(b, "/gen_diagnostics", "diagnostic_msgs/DiagnosticArray")
    pub = roslibpy.Topic(a, "/gen_diagnostics", "diagnostic_msgs/DiagnosticArray")
    pub.advertise()
    publish_until(pub, {"status": [{"level": 2, "name": "gen: widget", "message": "broken"}]}, got, "/gen_diagnostics")
    assert got[0]["status"][0]["level"] == 2 and got[0]["status"][0]["name"] == "gen: widget"
