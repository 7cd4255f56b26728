"""advertise / unadvertise: a client announces topics it will publish (shared rospy.Publisher)."""
from __future__ import annotations

from typing import Any, Dict

from ..protocol import check, number, require
from ..ros_plumbing import resolve_topic


def advertise(client: Any, msg: Dict[str, Any]) -> None:
    topic = resolve_topic(require(msg, "topic", str))
    type_name = require(msg, "type", str)
    latch = check(msg, "latch", bool, False)
    queue_size = int(number(msg, "queue_size", 100, maximum=100_000))
    _register(client, topic, type_name, latch, queue_size)


def _register(client: Any, topic: str, type_name: Any, latch: bool, queue_size: int) -> Any:
    with client.lock:
        pub = client.context.publishers.register(client.id, topic, type_name, latch, queue_size)
        client.advertised[topic] = client.advertised.get(topic, 0) + 1
        return pub


def ensure_publisher(client: Any, topic: str, latch: bool) -> Any:
    """publish without advertise: rosbridge registers implicitly when the topic's type is known."""
    pub = client.context.publishers.get(topic)
    if pub is not None and client.id in pub.clients:
        return pub
    return _register(client, topic, None, latch, 100)


def unadvertise(client: Any, msg: Dict[str, Any]) -> None:
    topic = resolve_topic(require(msg, "topic", str))
    with client.lock:
        if topic not in client.advertised:
            client.status("warning", f"{topic} is not advertised by this client", op="unadvertise",
                          msg_id=msg.get("id"))
            return
        del client.advertised[topic]
        client.context.publishers.unregister(client.id, topic)


def finish(client: Any) -> None:
    with client.lock:
        for topic in list(client.advertised):
            client.context.publishers.unregister(client.id, topic)
        client.advertised.clear()
