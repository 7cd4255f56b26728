"""The bridge's ROS 1 side (rospy): shared subscribers and publishers (shared.py) on TCPROS, service calls and
services served for a client, the master's graph.
"""
from __future__ import annotations

import logging
import threading
from typing import Any, Callable, Dict, Hashable, List, Optional, Set, Tuple

import rosgraph
import rospy
import rosservice

from . import conversion, shared
from .replay import ReplayBuffer
from .shared import ActionGoalError, ServiceCallError, SharedMessage, TopicError

log = logging.getLogger("rosbridge")
ServiceFailure = rospy.ServiceException  # what a served service's handler raises to fail the ROS caller


def _queued_write(self: Any, data: Any) -> bool:
    """rospy's QueuedConnection.write_data without its trailing time.sleep(0)."""
    with self._lock:
        if self._error:  # an error of the connection's sending thread surfaces here, as in rospy
            error = self._error
            self._error = None
            raise error
        if self._queue_size > 0 and len(self._queue) == self._queue_size:
            del self._queue[0]
        self._queue.append(data)
        self._cond_data_available.notify()
    return True


def publish_without_yield() -> bool:
    """Make rospy's queued publish return without yielding the GIL; True when applied.

    rospy ends every queued write with time.sleep(0) so the connection's sending thread runs at once. Here every
    client's publish runs on the WebSocket loop thread, and each sleep(0) hands the GIL to one of dozens of busy
    threads: the loop then waits up to a switch interval (5 ms) to get it back. 25 clients at 100 Hz beside the
    simulated cell made that ~200 publishes a second at most; the loop fell behind its input for good and sent
    nobody anything (the soak's 'silent' clients). Without the sleep the sending thread is still notified and runs
    at the next switch. Applied only to the rospy this was written against (the method as described).
    """
    from rospy.impl.tcpros_pubsub import QueuedConnection
    current = QueuedConnection.write_data
    if current is _queued_write:
        return True
    names = set(getattr(current, "__code__", None).co_names) if hasattr(current, "__code__") else set()
    if not {"sleep", "_cond_data_available", "_queue_size", "_error"} <= names:
        log.warning("rospy's QueuedConnection.write_data is not the one expected: left as it is")
        return False
    QueuedConnection.write_data = _queued_write  # type: ignore[method-assign]
    return True


class SharedMaster:
    """One master proxy for every thread, one call at a time (an XML-RPC connection is not safe to share; master
    queries take about a millisecond). A rosgraph.Master per query, as rosservice.get_service_type and
    rospy.ServiceProxy.call make one, leaves its socket to the garbage collector, whose "unclosed socket"
    ResourceWarning text (unique per port) piles up in a warnings registry: ~250 B a query, the soak's steady
    growth at 1,500 service calls a minute."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._master: Optional[rosgraph.Master] = None

    def __getattr__(self, name: str) -> Any:
        def call(*args: Any) -> Any:
            with self._lock:
                if self._master is None:
                    self._master = rosgraph.Master(rospy.get_name() or "/rosbridge")
                return getattr(self._master, name)(*args)
        return call


master = SharedMaster()


def master_topic_types() -> Dict[str, str]:
    """topic -> type for every topic the master knows (published or subscribed)."""
    return {t: ty for t, ty in master.getTopicTypes() if ty and ty != "*"}


def resolve_topic(name: Any) -> str:
    if not isinstance(name, str) or not name.strip():
        raise TopicError(f"invalid topic name {name!r}")
    name = name.strip()
    resolved = rosgraph.names.resolve_name(name, "/")
    if not rosgraph.names.is_legal_name(resolved):
        raise TopicError(f"illegal ROS name '{name}'")
    return resolved


class SharedSubscriber(shared.SharedSubscriber):
    def __init__(self, topic: str, type_name: str, msg_cls: type) -> None:
        super().__init__(topic, type_name, msg_cls)
        # Bounded: if conversion ever falls behind a flood, rospy drops the oldest instead of growing.
        self.sub = rospy.Subscriber(topic, msg_cls, self._callback, queue_size=100, tcp_nodelay=True)

    def _callback(self, msg: Any) -> None:
        now = rospy.get_rostime()
        header = getattr(msg, "_connection_header", None) or {}
        self.deliver(SharedMessage(self.topic, msg, (now.secs, now.nsecs)), str(header.get("callerid", "")),
                     header.get("latching") == "1")

    def unregister(self) -> None:
        self.sub.unregister()


class TopicHub(shared.TopicHub):
    subscriber_class = SharedSubscriber
    topic_types = staticmethod(master_topic_types)


class ReplayListener(rospy.SubscribeListener):
    """Hands a new publisher's first messages (ReplayBuffer) to subscribers whose connection came late.

    Works on the rospy _PublisherImpl (shared by every rospy.Publisher of the topic in this process).
    Peers are connection objects: a connection that replaces another one of the same node (rospy drops
    the old one, with whatever it still had queued) counts as new and gets the whole replay.
    Lock order: the impl's publock, then its c_lock; rospy never takes them the other way round.
    """

    def __init__(self, impl: Any, buffer: ReplayBuffer[Any]) -> None:
        self._impl = impl
        self.buffer = buffer

    def publish(self, pub: rospy.Publisher, msg: Any) -> bool:
        """Publish and keep `msg`; False (nothing done) once the window is over."""
        impl = self._impl
        impl.acquire()
        try:
            if impl.closed or not self.buffer.is_open():
                return False
            # No subscriber may join between listing who gets this message and writing it: it would
            # get it now and once more from the replay.
            with impl.c_lock:
                reached = list(impl.connections)
                pub.publish(msg)
            self.buffer.record(msg, reached)
            return True
        finally:
            impl.release()

    def peer_subscribe(self, topic_name: str, topic_publish: Any, peer_publish: Any) -> None:
        # Called by rospy in the new connection's thread, after the connection joined the impl and
        # before a latching publisher's last message is sent to it.
        impl = self._impl
        impl.acquire()  # no publish can slip between the replayed messages: order is kept
        try:
            if impl.closed or not self.buffer.is_open():
                return
            latch = impl.latch if impl.is_latch else None
            # Every connection, not just this call's: another one may have joined meanwhile; the
            # buffer knows who got what, so nobody receives a message twice.
            for conn in list(impl.connections):
                for msg in self.buffer.missed(conn, skip=latch):
                    impl.publish(msg, connection_override=conn)
            if impl.is_latch:
                impl.latch = latch  # impl.publish latched the replayed (older) message: undo that
        except Exception:  # never break rospy's connection setup
            log.exception("replay to a new subscriber of %s failed", topic_name)
        finally:
            impl.release()

    def detach(self) -> None:
        impl = self._impl
        impl.acquire()  # peer_subscribe may be walking the buffer in rospy's thread
        try:
            self.buffer.close()
        finally:
            impl.release()
        listeners = getattr(self._impl, "subscriber_listeners", None)
        if listeners:
            # A new list, not remove(): rospy may be iterating over the old one in another thread.
            self._impl.subscriber_listeners = [x for x in listeners if x is not self]


class SharedPublisher:
    def __init__(self, topic: str, type_name: str, msg_cls: type, latch: bool, queue_size: int,
                 replay_window: float = 1.0, replay_max: int = 100) -> None:
        self.topic, self.type_name, self.msg_cls, self.latch = topic, type_name, msg_cls, latch
        self.clients: Set[Hashable] = set()
        self.pub = rospy.Publisher(topic, msg_cls, latch=latch, queue_size=max(1, queue_size),
                                   tcp_nodelay=True)
        self._replay: Optional[ReplayListener] = None
        if replay_window > 0 and replay_max > 0:
            # Started after the master registration above: the window covers the time existing
            # subscribers need to hear of us and connect.
            self._replay = ReplayListener(self.pub.impl, ReplayBuffer(replay_window, replay_max))
            self.pub.impl.add_subscriber_listener(self._replay)

    def publish(self, msg: Any) -> None:
        replay = self._replay
        if replay is not None:
            if replay.publish(self.pub, msg):
                return
            self._replay = None  # window over: plain publishing from now on
            replay.detach()
        self.pub.publish(msg)

    def unregister(self) -> None:
        replay, self._replay = self._replay, None
        if replay is not None:
            replay.detach()
        self.pub.unregister()


class _LookedUpProxy(rospy.ServiceProxy):
    """A ServiceProxy for a URI looked up already: rospy's own call looks it up again with a master of its own."""

    def __init__(self, name: str, service_class: type, uri: str) -> None:
        super().__init__(name, service_class)
        self._looked_up = uri

    def _get_service_uri(self, request: Any) -> str:
        self.uri = self._looked_up
        return self.uri


class PublisherRegistry(shared.PublisherRegistry):
    publisher_class = SharedPublisher


def call_service(name: str, args: Any) -> Tuple[str, Any]:
    """Blocking call of a ROS service by name; returns (service type, response message).

    A missing or dead service raises ServiceCallError quickly (master lookup + connect refused on loopback).
    """
    try:
        uri = master.lookupService(name)
    except rosgraph.MasterError:
        raise ServiceCallError(f"service {name} does not exist") from None
    except Exception as exc:
        raise ServiceCallError(f"service {name} is not reachable: {exc}") from exc
    try:
        type_name = rosservice.get_service_headers(name, uri).get("type", "")
    except Exception as exc:
        raise ServiceCallError(f"service {name} is not reachable: {exc}") from exc
    if not type_name:
        raise ServiceCallError(f"service {name} does not exist")
    srv_cls = conversion.get_service_class(type_name)
    request = conversion.args_to_request(conversion.request_class(srv_cls), args)
    proxy = _LookedUpProxy(name, srv_cls, uri)
    try:
        return type_name, proxy.call(request)
    except rospy.ServiceException as exc:
        raise ServiceCallError(f"service {name} failed: {exc}") from exc
    finally:
        proxy.close()


def serve(name: str, srv_cls: type, handler: Callable[[Any], Any]) -> Callable[[str], None]:
    """Offer a ROS service whose requests `handler` answers (raising ServiceFailure fails the caller); returns
    the function that withdraws it."""
    service = rospy.Service(name, srv_cls, handler)
    return service.shutdown


def other_providers(name: str) -> List[str]:
    """Nodes other than this one serving `name`: the master would silently hand the name to us."""
    _, _, services = master.getSystemState()
    me = rospy.get_name()
    return [n for s, nodes in services if s == name for n in nodes if n != me]


def send_action_goal(name: str, type_name: str, args: Any, on_feedback: Callable[[Any], None],
                     on_handle: Callable[[Any], None]) -> Tuple[int, Any]:
    """The action ops are rosbridge_suite's ROS 2 protocol: on ROS 1 a client speaks to an action server through
    its goal, cancel, feedback and result topics (roslib's ActionClient)."""
    raise ActionGoalError(f"send_action_goal needs a ROS 2 server; on ROS 1 use the topics of {name} (actionlib)")
