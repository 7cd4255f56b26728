"""rospy's queued publish without its time.sleep(0): same queueing (drop-oldest, errors surfaced), no GIL hand-over on
the caller's thread (the rosbridge loop's)."""
from __future__ import annotations

import threading
import time
from unittest import mock

from rospy.impl.tcpros_pubsub import QueuedConnection

from cell_rosbridge.plumbing_ros1 import publish_without_yield


class _Conn:
    done = False


def _queued(queue_size: int) -> QueuedConnection:
    # A QueuedConnection's state without its sending thread (the test reads the queue itself).
    q = QueuedConnection.__new__(QueuedConnection)
    q._connection = _Conn()
    q._queue_size = queue_size
    q._lock = threading.Lock()
    q._cond_data_available = threading.Condition(q._lock)
    q._queue = []
    q._error = None
    return q


def test_queued_write_keeps_rospys_queueing_and_never_sleeps():
    original = QueuedConnection.write_data
    try:
        with mock.patch.object(time, "sleep") as sleep:
            original(_queued(2), b"a")
        assert sleep.call_count == 1  # rospy as shipped yields after every write (what this replaces)
        assert publish_without_yield()
        assert publish_without_yield()  # twice: still applied, not wrapped again
        q = _queued(2)
        with mock.patch.object(time, "sleep") as sleep:
            for data in (b"1", b"2", b"3"):
                assert q.write_data(data) is True
        sleep.assert_not_called()
        assert q._queue == [b"2", b"3"]  # drop-oldest at queue_size, as rospy
        unbounded = _queued(0)
        for i in range(5):
            unbounded.write_data(bytes([i]))
        assert len(unbounded._queue) == 5
        q._error = RuntimeError("connection lost")  # the sending thread's error surfaces once, as in rospy
        try:
            q.write_data(b"4")
        except RuntimeError as e:
            assert str(e) == "connection lost"
        else:
            raise AssertionError("the sending thread's error was not raised")
        assert q.write_data(b"5") and q._queue[-1] == b"5"
    finally:
        QueuedConnection.write_data = original


def test_a_waiting_sender_is_woken():
    original = QueuedConnection.write_data
    try:
        publish_without_yield()
        q = _queued(10)
        got: list[bytes] = []

        def sender() -> None:
            with q._lock:
                while not q._queue:
                    q._cond_data_available.wait()
                got.extend(q._queue)

        t = threading.Thread(target=sender)
        t.start()
        q.write_data(b"x")
        t.join(5)
        assert got == [b"x"]
    finally:
        QueuedConnection.write_data = original
