"""A new client publisher must not lose its first messages to ROS subscribers that are still connecting.

rosbridge_suite's own smoke test: a client advertises (or just publishes to) a topic and sends 10 messages
at once; a rospy subscriber that existed before must get all 10, in order, once.
"""
from __future__ import annotations

import subprocess
import sys
import threading
import time
from typing import Any, List

import pytest
import rospy
import std_msgs.msg as std

from rb_helpers import BridgeProcess, subscribers_of, wait_for
from rb_wsclient import WSClient

# A second ROS node (its own TCPROS connection) that prints what it receives, one line per message.
# Each line is one write under a lock: print() writes the text and the newline separately, so the callback
# thread's line and the main thread's READY could interleave.
_ECHO = """
import sys, threading, rospy, std_msgs.msg as std
rospy.init_node("replay_echo", anonymous=True, disable_signals=True)
_lock = threading.Lock()
def say(text):
    with _lock:
        sys.stdout.write(text + "\\n")
        sys.stdout.flush()
def cb(m):
    say(m.data)
sub = rospy.Subscriber(sys.argv[1], std.String, cb, queue_size=100)
import time
t0 = time.monotonic()
while sub.get_num_connections() == 0 and time.monotonic() - t0 < 15:
    time.sleep(0.01)
say("READY")
time.sleep(float(sys.argv[2]))
"""


class Collector:
    def __init__(self, topic: str) -> None:
        self.got: List[str] = []
        self._lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, std.String, self._cb, queue_size=100)

    def _cb(self, msg: Any) -> None:
        with self._lock:
            self.got.append(msg.data)

    def settle(self, expected: int, timeout: float = 10.0, grace: float = 0.4) -> List[str]:
        """Wait for `expected` messages (or the timeout), then a little longer to catch duplicates."""
        deadline = time.monotonic() + timeout
        while len(self.got) < expected and time.monotonic() < deadline:
            time.sleep(0.02)
        time.sleep(grace)
        with self._lock:
            return list(self.got)


def _burst(c: WSClient, topic: str, first: int, count: int) -> None:
    for i in range(first, first + count):
        c.send_json({"op": "publish", "topic": topic, "msg": {"data": f"m{i}"}})


def _names(first: int, count: int) -> List[str]:
    return [f"m{i}" for i in range(first, first + count)]


@pytest.mark.parametrize("advertise", [True, False], ids=["advertise_then_publish", "publish_without_advertise"])
def test_subscriber_that_exists_before_gets_all_ten_in_order(ros_node: str, bridge: BridgeProcess,
                                                             advertise: bool) -> None:
    topic = f"/replay_first_{'adv' if advertise else 'implicit'}"
    col = Collector(topic)
    wait_for(lambda: ros_node in subscribers_of(topic), 5, what="test subscriber registered")
    c = WSClient(bridge.port)
    try:
        if advertise:
            c.send_json({"op": "advertise", "topic": topic, "type": "std_msgs/String"})
        _burst(c, topic, 0, 10)  # straight away, as rosbridge_suite's smoke test does
        got = col.settle(10)
        assert got == _names(0, 10), f"{len(got)} of 10 arrived: {got}"
    finally:
        c.close()
        col.sub.unregister()


def test_connected_subscriber_gets_no_duplicates_when_another_joins_in_the_window(
        ros_node: str, make_bridge: Any) -> None:
    # A long window so a second node (a process start) surely connects inside it on a loaded machine.
    b = make_bridge(params={"publisher_replay_window": 8.0})
    topic = "/replay_dup"
    first = Collector(topic)
    wait_for(lambda: ros_node in subscribers_of(topic), 5, what="test subscriber registered")
    c = WSClient(b.port)
    echo = subprocess.Popen([sys.executable, "-c", _ECHO, topic, "2.0"], stdout=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        c.send_json({"op": "advertise", "topic": topic, "type": "std_msgs/String"})
        _burst(c, topic, 0, 10)
        got = first.settle(10, grace=0.0)
        assert got == _names(0, 10), f"first subscriber: {got}"
        lines: List[str] = []
        assert echo.stdout is not None
        for line in echo.stdout:  # the late joiner gets the replay before anything new
            lines.append(line.strip())
            if lines[-1] == "READY":
                break
        _burst(c, topic, 10, 1)
        out, _ = echo.communicate(timeout=20)
        lines += out.split()
        assert [x for x in lines if x != "READY"] == _names(0, 11), f"second subscriber: {lines}"
        got = first.settle(11)
        assert got == _names(0, 11), f"first subscriber: {got}"  # the newcomer's replay did not reach it
    finally:
        if echo.poll() is None:
            echo.terminate()
            echo.wait(5)
        c.close()
        first.sub.unregister()


def test_subscriber_connecting_after_the_window_gets_no_stale_messages(ros_node: str,
                                                                       bridge: BridgeProcess) -> None:
    topic = "/replay_late"
    c = WSClient(bridge.port)
    try:
        c.send_json({"op": "advertise", "topic": topic, "type": "std_msgs/String"})
        _burst(c, topic, 0, 3)  # nobody listens yet
        time.sleep(1.3)  # past the 1 s window
        col = Collector(topic)
        wait_for(lambda: col.sub.get_num_connections() > 0, 5, what="late subscriber connected")
        time.sleep(0.3)
        assert col.got == []
        _burst(c, topic, 3, 1)
        assert col.settle(1) == ["m3"]
        col.sub.unregister()
    finally:
        c.close()
