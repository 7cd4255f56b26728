"""The generation-neutral half of the bridge's ROS side: one subscriber per topic shared by every client, shared
publishers with their hold-over, the encoded forms of a message cached for all clients.

Why shared: N browser tabs on one topic must cost one ROS subscription and one conversion per message, not N.
Each generation's plumbing (plumbing_ros1, plumbing_ros2) binds these to its ROS client library: what a subscriber,
a publisher and the graph's topic types are there.
"""
from __future__ import annotations

import itertools
import logging
import threading
from typing import Any, Callable, Dict, Hashable, List, Optional, Tuple

from . import conversion, encoding
from .encoding import Frame

log = logging.getLogger("rosbridge")
_message_ids = itertools.count(1)


class TopicError(ValueError):
    pass


class ServiceCallError(RuntimeError):
    pass


class ActionGoalError(RuntimeError):
    """A goal that could not run: no such server, rejected, the client library failed."""


class SharedMessage:
    """One received ROS message plus its encodings, each computed at most once (thread-safe)."""

    __slots__ = ("topic", "msg", "frag_id", "stamp", "_cache", "_lock")

    def __init__(self, topic: str, msg: Any, stamp: Tuple[int, int] = (0, 0)) -> None:
        self.topic = topic
        self.msg = msg
        self.frag_id = f"publish:{topic}:{next(_message_ids)}"
        self.stamp = stamp  # receipt time (secs, nsecs), for cbor-raw
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
    """One ROS subscription of a topic and the clients listening to it. A generation's subclass makes the
    subscription in `__init__` (after calling this one) and hands each message to `deliver`; `unregister` ends it."""

    def __init__(self, topic: str, type_name: str, msg_cls: type) -> None:
        self.topic, self.type_name, self.msg_cls = topic, type_name, msg_cls
        self.listeners: Dict[Hashable, Listener] = {}
        # The last message of each latching publisher (by publisher id): a topic such as /tf_static has several,
        # and ROS hands a new subscriber every one of them.
        self.latched: Dict[str, SharedMessage] = {}
        self._lock = threading.Lock()

    def deliver(self, shared: SharedMessage, publisher: str, latching: bool) -> None:
        with self._lock:
            if latching:
                self.latched[publisher] = shared
            else:
                self.latched.pop(publisher, None)
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
        # ROS delivers a latched message once per subscription; a client joining an existing
        # subscription would otherwise never see it (e.g. the cell's operation mode).
        for shared in replay:
            listener(shared)

    def unregister(self) -> None:
        raise NotImplementedError


class TopicHub:
    """Shared subscribers by topic; released when the last listener leaves. A generation binds
    `subscriber_class` and `topic_types` (the graph's topic -> type, in 'pkg/Type' form)."""

    subscriber_class: Callable[[str, str, type], SharedSubscriber]

    @staticmethod
    def topic_types() -> Dict[str, str]:
        raise NotImplementedError

    def __init__(self) -> None:
        self._subs: Dict[str, SharedSubscriber] = {}
        self._lock = threading.RLock()

    def count(self) -> int:
        return len(self._subs)

    def subscribe(self, topic: str, type_name: Optional[str], key: Hashable, listener: Listener,
                  known_types: Optional[Callable[[], Dict[str, str]]] = None) -> str:
        with self._lock:
            shared = self._subs.get(topic)
            if shared is None:
                actual = (known_types or self.topic_types)().get(topic)
                if type_name:
                    wanted = conversion.normalize_type(type_name)
                    if actual and actual != wanted:
                        raise TopicError(f"topic {topic} has type {actual}, not {wanted}")
                elif actual:
                    wanted = actual
                else:
                    raise TopicError(f"cannot infer the type of {topic}: it does not exist; give 'type'")
                msg_cls = conversion.get_message_class(wanted)
                shared = self._subs[topic] = self.subscriber_class(topic, wanted, msg_cls)
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
                shared.unregister()

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
                shared.unregister()
            self._subs.clear()


class PublisherRegistry:
    """Shared publishers by topic; each client that advertised (or published) holds a reference.

    When the last client lets go, the publisher stays registered for `unregister_timeout` seconds more (as
    rosbridge_suite's `unregister_timeout`, default 10 s) and a client advertising meanwhile takes it over. Why: a
    rospy subscriber that hears of a publisher and connects just after it is unregistered gets "not a publisher",
    gives up, and keeps that dead connection; it then ignores every later publisher of the topic at the same
    address (this node), so a page that left the Manual page at once broke jogging for the next one until
    rosbridge restarted (rosbridge_suite #138, ros_comm #111).
    """

    publisher_class: Callable[..., Any]  # (topic, type, msg_cls, latch, queue_size, replay_window, replay_max)

    def __init__(self, hub: TopicHub, replay_window: float = 1.0, replay_max: int = 100,
                 unregister_timeout: float = 10.0) -> None:
        self._pubs: Dict[str, Any] = {}
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

    def get(self, topic: str) -> Optional[Any]:
        return self._pubs.get(topic)

    def register(self, client: Hashable, topic: str, type_name: Optional[str], latch: bool = False,
                 queue_size: int = 100) -> Any:
        with self._lock:
            pub = self._pubs.get(topic)
            if pub is not None and not pub.clients and type_name \
                    and conversion.normalize_type(type_name) != pub.type_name:
                self._drop(topic)  # nobody holds the old type's publisher: the new client's type wins
                pub = None
            if pub is None:
                actual = self._hub.topic_types().get(topic) or self._hub.type_of(topic)
                if type_name:
                    wanted = conversion.normalize_type(type_name)
                    msg_cls = conversion.get_message_class(wanted)
                    if actual and actual != wanted:
                        raise TopicError(f"topic {topic} already has type {actual}, not {wanted}")
                elif actual:
                    wanted, msg_cls = actual, conversion.get_message_class(actual)
                else:
                    raise TopicError(f"topic {topic} does not exist and no type was given")
                pub = self._pubs[topic] = self.publisher_class(topic, wanted, msg_cls, latch, queue_size,
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

    def _expire(self, topic: str, pub: Any) -> None:
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


