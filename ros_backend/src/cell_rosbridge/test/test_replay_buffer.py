"""The publisher replay without a master or sockets: the buffer's rules, then the rospy glue on a fake impl."""
from __future__ import annotations

import threading
from typing import Any, List, Optional, Tuple

from cell_rosbridge.replay import ReplayBuffer


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_a_peer_gets_what_it_missed_once_in_order() -> None:
    clock = Clock()
    buf: ReplayBuffer[str] = ReplayBuffer(window=1.0, max_messages=10, clock=clock)
    for i in range(3):
        assert buf.record(f"m{i}", reached=[])
    assert buf.missed("late") == ["m0", "m1", "m2"]
    assert buf.missed("late") == []  # asked again (e.g. another connection's turn): nothing twice


def test_peers_that_were_connected_get_nothing_again() -> None:
    buf: ReplayBuffer[str] = ReplayBuffer(window=1.0, max_messages=10, clock=Clock())
    buf.record("m0", reached=[])
    buf.record("m1", reached=["early"])  # "early" connected between m0 and m1
    buf.record("m2", reached=["early", "other"])
    assert buf.missed("early") == ["m0"]
    assert buf.missed("other") == ["m0", "m1"]
    assert buf.missed("new") == ["m0", "m1", "m2"]


def test_nothing_is_kept_or_replayed_after_the_window() -> None:
    clock = Clock()
    buf: ReplayBuffer[str] = ReplayBuffer(window=1.0, max_messages=10, clock=clock)
    buf.record("m0", reached=[])
    clock.now += 0.999
    assert buf.record("m1", reached=[])
    clock.now += 0.002  # 1.001 s after creation
    assert not buf.record("m2", reached=[])
    assert buf.missed("late") == []
    assert len(buf) == 0  # freed, not just hidden
    assert not buf.is_open()


def test_count_cap_drops_the_oldest() -> None:
    buf: ReplayBuffer[int] = ReplayBuffer(window=1.0, max_messages=3, clock=Clock())
    for i in range(5):
        buf.record(i, reached=[])
    assert len(buf) == 3
    assert buf.missed("p") == [2, 3, 4]


def test_zero_window_or_cap_disables() -> None:
    for window, cap in ((0.0, 10), (1.0, 0)):
        buf: ReplayBuffer[int] = ReplayBuffer(window=window, max_messages=cap, clock=Clock())
        assert not buf.record(1, reached=[])
        assert buf.missed("p") == []


def test_skip_is_marked_delivered_but_not_returned() -> None:
    buf: ReplayBuffer[Any] = ReplayBuffer(window=1.0, max_messages=10, clock=Clock())
    a, b = object(), object()
    buf.record(a, reached=[])
    buf.record(b, reached=[])
    assert buf.missed("p", skip=b) == [a]  # rospy sends the latched b itself
    assert buf.missed("p") == []


# ---------------------------------------------------------------- rospy glue on a fake _PublisherImpl
class FakeConn:
    def __init__(self, name: str) -> None:
        self.endpoint_id = name
        self.got: List[Any] = []


class FakeImpl:
    """The parts of rospy's _PublisherImpl that ReplayListener relies on (ros_comm 1.15)."""

    def __init__(self, latch: bool = False) -> None:
        self.publock = threading.RLock()
        self.c_lock = threading.RLock()
        self.connections: List[FakeConn] = []
        self.subscriber_listeners: List[Any] = []
        self.closed = False
        self.is_latch = latch
        self.latch: Any = None

    def acquire(self) -> None:
        self.publock.acquire()

    def release(self) -> None:
        self.publock.release()

    def add_subscriber_listener(self, listener: Any) -> None:
        self.subscriber_listeners.append(listener)

    def publish(self, msg: Any, connection_override: Optional[FakeConn] = None) -> None:
        if self.is_latch:
            self.latch = msg
        for c in [connection_override] if connection_override else self.connections:
            c.got.append(msg)

    def add_connection(self, conn: FakeConn) -> None:  # what rospy does when a subscriber connects
        with self.c_lock:
            self.connections = self.connections + [conn]
        for listener in self.subscriber_listeners:
            listener.peer_subscribe("/t", self.publish, lambda m: self.publish(m, connection_override=conn))
        if self.is_latch and self.latch is not None:
            with self.publock:
                self.publish(self.latch, connection_override=conn)


class FakePub:
    def __init__(self, impl: FakeImpl) -> None:
        self.impl = impl

    def publish(self, msg: Any) -> None:
        with self.impl.publock:
            self.impl.publish(msg)


def _listener(latch: bool = False, window: float = 1.0) -> Tuple[Any, FakeImpl, FakePub, Clock]:
    from cell_rosbridge.plumbing_ros1 import ReplayListener
    clock = Clock()
    impl = FakeImpl(latch)
    listener = ReplayListener(impl, ReplayBuffer(window, 100, clock=clock))
    impl.add_subscriber_listener(listener)
    return listener, impl, FakePub(impl), clock


def test_glue_replays_to_late_connections_without_duplicates() -> None:
    listener, impl, pub, clock = _listener()
    early = FakeConn("/early")
    impl.add_connection(early)
    for i in range(3):
        assert listener.publish(pub, i)
    late = FakeConn("/late")
    impl.add_connection(late)  # replay 0..2 to it; "early" had them already
    assert listener.publish(pub, 3)
    assert early.got == [0, 1, 2, 3]
    assert late.got == [0, 1, 2, 3]
    clock.now += 1.5
    after = FakeConn("/after_window")
    impl.add_connection(after)
    assert after.got == []
    assert not listener.publish(pub, 4)  # the caller publishes plainly from now on


def test_glue_latched_topic_replays_older_messages_and_keeps_the_latest_latched() -> None:
    listener, impl, pub, _ = _listener(latch=True)
    for i in range(3):
        listener.publish(pub, i)
    sub = FakeConn("/sub")
    impl.add_connection(sub)
    assert sub.got == [0, 1, 2]  # 0, 1 replayed, 2 sent by rospy's latch: once each, in order
    assert impl.latch == 2


def test_glue_detach_removes_the_listener() -> None:
    listener, impl, pub, _ = _listener()
    listener.detach()
    assert impl.subscriber_listeners == []
    assert not listener.publish(pub, 1)
