"""subscribe / unsubscribe.

Per client and topic there is one TopicSubscription holding every subscription id of that client; the
spec merges them (lowest throttle_rate and fragment_size, highest queue_length) since publish messages
carry no id. Across clients nothing is merged: each client has its own outbox lane with its own
throttle and queue, fed from the one shared rospy subscriber.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any, Dict, Hashable, Optional, Tuple

from ..conversion import normalize_type
from ..op_base import COMPRESSIONS, ProtocolError, check, number, require
from ..plumbing import SharedMessage, resolve_topic

_anon = itertools.count(1)


@dataclass
class SubParams:
    throttle_rate: int
    queue_length: int
    fragment_size: int
    compression: str


class TopicSubscription:
    def __init__(self, client: Any, topic: str) -> None:
        self.client = client
        self.topic = topic
        self.lane: Hashable = ("sub", topic)
        self.sids: Dict[Any, SubParams] = {}
        self.type_name: Optional[str] = None
        self._send: Tuple[str, int] = ("none", 0)  # (compression, fragment_size): read by ROS threads

    def update(self) -> None:
        params = list(self.sids.values())
        throttle = min(p.throttle_rate for p in params)
        queue_length = max(p.queue_length for p in params)
        frags = [p.fragment_size for p in params if p.fragment_size > 0]
        self._send = (params[-1].compression, min(frags) if frags else 0)
        self.client.outbox.configure_lane(self.lane, queue_length, throttle)

    def on_message(self, shared: SharedMessage) -> None:
        compression, fragment_size = self._send
        frames, nbytes = shared.frames(compression, fragment_size)
        self.client.send_frames(frames, nbytes, self.lane)


def _int_field(msg: Dict[str, Any], name: str) -> int:
    return int(number(msg, name, 0))


def subscribe(client: Any, msg: Dict[str, Any]) -> None:
    topic = resolve_topic(require(msg, "topic", str))
    type_name = check(msg, "type", str, None) or None
    params = SubParams(_int_field(msg, "throttle_rate"), _int_field(msg, "queue_length"),
                       _int_field(msg, "fragment_size"), check(msg, "compression", str, "none"))
    if params.compression not in COMPRESSIONS:
        raise ProtocolError(f"unsupported compression '{params.compression}' (use one of {', '.join(COMPRESSIONS)})")
    sid = msg.get("id")
    if sid is None or isinstance(sid, (dict, list, bool)):
        sid = ("anon", next(_anon))
    hub = client.context.hub
    with client.lock:
        sub = client.subscriptions.get(topic)
        if sub is None:
            sub = TopicSubscription(client, topic)
            sub.sids[sid] = params
            sub.update()
            try:
                sub.type_name = hub.subscribe(topic, type_name, client.id, sub.on_message)
            except Exception:
                client.outbox.remove_lane(sub.lane)
                raise
            client.subscriptions[topic] = sub
            return
        if type_name and sub.type_name and normalize_type(type_name) != sub.type_name:
            raise ProtocolError(f"topic {topic} has type {sub.type_name}, not {type_name}")
        sub.sids[sid] = params
        sub.update()
    # A second subscription of the same client (another component, or another browser behind a
    # relay) must see the latched state too; duplicates are harmless for latched data.
    for last in hub.latched(topic):
        sub.on_message(last)


def unsubscribe(client: Any, msg: Dict[str, Any]) -> None:
    topic = resolve_topic(require(msg, "topic", str))
    sid = msg.get("id")
    with client.lock:
        sub = client.subscriptions.get(topic)
        if sub is None:
            client.status("warning", f"not subscribed to {topic}", op="unsubscribe", msg_id=sid)
            return
        if sid is not None:
            if sid not in sub.sids:
                client.status("warning", f"no subscription with id {sid!r} on {topic}", op="unsubscribe",
                              msg_id=sid)
                return
            del sub.sids[sid]
        else:  # spec: without an id, every subscription of this client to the topic ends
            sub.sids.clear()
        if sub.sids:
            sub.update()
            return
        del client.subscriptions[topic]
    _release(client, sub)


def _release(client: Any, sub: TopicSubscription) -> None:
    client.context.hub.unsubscribe(sub.topic, client.id)
    client.outbox.remove_lane(sub.lane)


def finish(client: Any) -> None:
    with client.lock:
        subs = list(client.subscriptions.values())
        client.subscriptions.clear()
    for sub in subs:
        _release(client, sub)
