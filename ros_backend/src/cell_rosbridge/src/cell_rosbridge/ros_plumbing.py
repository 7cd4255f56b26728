"""ROS side of the bridge: one rospy subscriber / publisher per topic shared by all clients, service calls.

Why shared: N browser tabs on one topic must cost one TCPROS connection and one conversion per message,
not N. Encoded forms are cached on the SharedMessage, so each encoding is produced once for all clients.
"""
from __future__ import annotations

import itertools
import logging
import threading
from typing import Any, Callable, Dict, Hashable, List, Optional, Set, Tuple

import rosgraph
import rospy
import rosservice

from . import conversion, encoding
from .encoding import Frame
from .replay import ReplayBuffer

log = logging.getLogger("rosbridge")
_message_ids = itertools.count(1)


class TopicError(ValueError):
    pass


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


class SharedMessage:
    """One received ROS message plus its encodings, each computed at most once (thread-safe)."""

    __slots__ = ("topic", "msg", "frag_id", "stamp", "_cache", "_lock")

    def __init__(self, topic: str, msg: Any) -> None:
        self.topic = topic
        self.msg = msg
        self.frag_id = f"publish:{topic}:{next(_message_ids)}"
        now = rospy.get_rostime()
        self.stamp = (now.secs, now.nsecs)  # receipt time, for cbor-raw
        self._cache: Dict[Tuple[str, int], Tuple[List[Frame], int]] = {}
        self._lock = threading.Lock()

    def frames(self, compression: str, fragment_size: int = 0) -> Tuple[List[Frame], int]:
        key = (compression, fragment_size if compression in ("none", "png") else 0)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        with self._lock:
            hit = self._cache.get(key)
            if hit is None:
                hit = self._cache[key] = self._encode(*key)
            return hit

    def _json_text(self) -> str:
        hit = self._cache.get(("json-text", 0))
        if hit is None:
            text = encoding.encode_json({"op": "publish", "topic": self.topic,
                                         "msg": conversion.msg_to_dict(self.msg)})
            hit = self._cache[("json-text", 0)] = ([text], len(text))
        return hit[0][0]  # type: ignore[return-value]

    def _encode(self, compression: str, fragment_size: int) -> Tuple[List[Frame], int]:
        if compression == "cbor":
            data = encoding.encode_cbor({"op": "publish", "topic": self.topic,
                                         "msg": conversion.msg_to_dict(self.msg, cbor=True)})
            return [data], len(data)
        if compression == "cbor-raw":
            secs, nsecs = self.stamp
            data = encoding.encode_cbor({"op": "publish", "topic": self.topic,
                                         "msg": {"secs": secs, "nsecs": nsecs,
                                                 "bytes": conversion.serialize(self.msg)}})
            return [data], len(data)
        frames = encoding.json_frames(self._json_text(), compression, fragment_size, self.frag_id)
        return frames, sum(len(f) for f in frames)


Listener = Callable[[SharedMessage], None]


class SharedSubscriber:
    def __init__(self, topic: str, type_name: str, msg_cls: type) -> None:
        self.topic, self.type_name, self.msg_cls = topic, type_name, msg_cls
        self.listeners: Dict[Hashable, Listener] = {}
        # The last message of each latching publisher (by caller id): a topic such as /tf_static has several,
        # and ROS hands a new subscriber every one of them.
        self.latched: Dict[str, SharedMessage] = {}
        self._lock = threading.Lock()
        # Bounded: if conversion ever falls behind a flood, rospy drops the oldest instead of growing.
        self.sub = rospy.Subscriber(topic, msg_cls, self._callback, queue_size=100, tcp_nodelay=True)

    def _callback(self, msg: Any) -> None:
        shared = SharedMessage(self.topic, msg)
        header = getattr(msg, "_connection_header", None) or {}
        caller = str(header.get("callerid", ""))
        with self._lock:
            if header.get("latching") == "1":
                self.latched[caller] = shared
            else:
                self.latched.pop(caller, None)
            listeners = list(self.listeners.values())
        for listener in listeners:
            try:
                listener(shared)
            except Exception:  # one broken client must not starve the others
                log.exception("listener failed on %s", self.topic)

    def add(self, key: Hashable, listener: Listener) -> None:
        with self._lock:
            self.listeners[key] = listener
            replay = list(self.latched.values())
        # rospy delivers a latched message once per connection; a client joining an existing
        # subscription would otherwise never see it (e.g. the cell's operation mode).
        for shared in replay:
            listener(shared)


class TopicHub:
    """Shared subscribers by topic; released when the last listener leaves."""

    def __init__(self) -> None:
        self._subs: Dict[str, SharedSubscriber] = {}
        self._lock = threading.RLock()

    def count(self) -> int:
        return len(self._subs)

    def subscribe(self, topic: str, type_name: Optional[str], key: Hashable, listener: Listener,
                  known_types: Callable[[], Dict[str, str]] = master_topic_types) -> str:
        with self._lock:
            shared = self._subs.get(topic)
            if shared is None:
                actual = known_types().get(topic)
                if type_name:
                    wanted = conversion.normalize_type(type_name)
                    if actual and actual != wanted:
                        raise TopicError(f"topic {topic} has type {actual}, not {wanted}")
                elif actual:
                    wanted = actual
                else:
                    raise TopicError(f"cannot infer the type of {topic}: it does not exist; give 'type'")
                msg_cls = conversion.get_message_class(wanted)
                shared = self._subs[topic] = SharedSubscriber(topic, wanted, msg_cls)
            elif type_name and conversion.normalize_type(type_name) != shared.type_name:
                raise TopicError(f"topic {topic} has type {shared.type_name}, not {type_name}")
        shared.add(key, listener)
        return shared.type_name

    def unsubscribe(self, topic: str, key: Hashable) -> None:
        with self._lock:
            shared = self._subs.get(topic)
            if shared is None:
                return
            with shared._lock:
                shared.listeners.pop(key, None)
                empty = not shared.listeners
            if empty:
                del self._subs[topic]
                shared.sub.unregister()

    def latched(self, topic: str) -> List[SharedMessage]:
        """The last message of each latching publisher of a topic."""
        shared = self._subs.get(topic)
        if shared is None:
            return []
        with shared._lock:
            return list(shared.latched.values())

    def type_of(self, topic: str) -> Optional[str]:
        shared = self._subs.get(topic)
        return shared.type_name if shared else None

    def shutdown(self) -> None:
        with self._lock:
            for shared in self._subs.values():
                shared.sub.unregister()
            self._subs.clear()


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


class PublisherRegistry:
    """Shared publishers by topic; each client that advertised (or published) holds a reference.

    When the last client lets go, the publisher stays registered for `unregister_timeout` seconds more (as
    rosbridge_suite's `unregister_timeout`, default 10 s) and a client advertising meanwhile takes it over. Why: a
    rospy subscriber that hears of a publisher and connects just after it is unregistered gets "not a publisher",
    gives up, and keeps that dead connection; it then ignores every later publisher of the topic at the same
    address (this node), so a page that left the Manual page at once broke jogging for the next one until
    rosbridge restarted (rosbridge_suite #138, ros_comm #111).
    """

    def __init__(self, hub: TopicHub, replay_window: float = 1.0, replay_max: int = 100,
                 unregister_timeout: float = 10.0) -> None:
        self._pubs: Dict[str, SharedPublisher] = {}
        self._lock = threading.RLock()
        self._hub = hub
        self._replay = (replay_window, replay_max)
        self._unregister_timeout = unregister_timeout
        self._timers: Dict[str, threading.Timer] = {}  # topic -> its pending unregistration

    def count(self) -> int:
        """Publishers some client holds (not those waiting out their unregister timeout)."""
        with self._lock:
            return sum(1 for p in self._pubs.values() if p.clients)

    def lingering(self) -> int:
        """Publishers no client holds any more, still registered until their unregister timeout."""
        with self._lock:
            return len(self._timers)

    def get(self, topic: str) -> Optional[SharedPublisher]:
        return self._pubs.get(topic)

    def register(self, client: Hashable, topic: str, type_name: Optional[str], latch: bool = False,
                 queue_size: int = 100) -> SharedPublisher:
        with self._lock:
            pub = self._pubs.get(topic)
            if pub is not None and not pub.clients and type_name \
                    and conversion.normalize_type(type_name) != pub.type_name:
                self._drop(topic)  # nobody holds the old type's publisher: the new client's type wins
                pub = None
            if pub is None:
                actual = master_topic_types().get(topic) or self._hub.type_of(topic)
                if type_name:
                    wanted = conversion.normalize_type(type_name)
                    msg_cls = conversion.get_message_class(wanted)
                    if actual and actual != wanted:
                        raise TopicError(f"topic {topic} already has type {actual}, not {wanted}")
                elif actual:
                    wanted, msg_cls = actual, conversion.get_message_class(actual)
                else:
                    raise TopicError(f"topic {topic} does not exist and no type was given")
                pub = self._pubs[topic] = SharedPublisher(topic, wanted, msg_cls, latch, queue_size,
                                                          *self._replay)
            elif type_name and conversion.normalize_type(type_name) != pub.type_name:
                raise TopicError(f"topic {topic} already has type {pub.type_name}, not {type_name}")
            timer = self._timers.pop(topic, None)
            if timer is not None:
                timer.cancel()  # taken over before its unregister timeout
            pub.clients.add(client)
            return pub

    def unregister(self, client: Hashable, topic: str) -> bool:
        with self._lock:
            pub = self._pubs.get(topic)
            if pub is None or client not in pub.clients:
                return False
            pub.clients.discard(client)
            if not pub.clients:
                if self._unregister_timeout > 0:
                    timer = threading.Timer(self._unregister_timeout, self._expire, (topic, pub))
                    timer.daemon = True
                    self._timers[topic] = timer
                    timer.start()
                else:
                    self._drop(topic)
            return True

    def _expire(self, topic: str, pub: SharedPublisher) -> None:
        with self._lock:
            if self._pubs.get(topic) is not pub or pub.clients:
                return  # taken over meanwhile
            self._timers.pop(topic, None)
            del self._pubs[topic]
        # The master's call outside the lock: an advertise or publish meanwhile need not wait for it (a new publisher
        # of the topic is safe: rospy counts the topic's publishers itself).
        pub.unregister()

    def _drop(self, topic: str) -> None:
        """Caller holds the lock."""
        timer = self._timers.pop(topic, None)
        if timer is not None:
            timer.cancel()
        pub = self._pubs.pop(topic, None)
        if pub is not None:
            pub.unregister()

    def shutdown(self) -> None:
        with self._lock:
            for topic in list(self._pubs):
                self._drop(topic)


class ServiceCallError(RuntimeError):
    pass


class _LookedUpProxy(rospy.ServiceProxy):
    """A ServiceProxy for a URI looked up already: rospy's own call looks it up again with a master of its own."""

    def __init__(self, name: str, service_class: type, uri: str) -> None:
        super().__init__(name, service_class)
        self._looked_up = uri

    def _get_service_uri(self, request: Any) -> str:
        self.uri = self._looked_up
        return self.uri


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
    request = conversion.args_to_request(srv_cls._request_class, args)
    proxy = _LookedUpProxy(name, srv_cls, uri)
    try:
        return type_name, proxy.call(request)
    except rospy.ServiceException as exc:
        raise ServiceCallError(f"service {name} failed: {exc}") from exc
    finally:
        proxy.close()
