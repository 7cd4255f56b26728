"""advertise / unadvertise: a client announces topics it will publish (shared rospy.Publisher)."""
from __future__ import annotations

from typing import Any, Dict

from ..op_base import check, number, register_publisher, require
from ..plumbing import resolve_topic


def advertise(client: Any, msg: Dict[str, Any]) -> None:
    topic = resolve_topic(require(msg, "topic", str))
    type_name = require(msg, "type", str)
    latch = check(msg, "latch", bool, False)
    queue_size = int(number(msg, "queue_size", 100, maximum=100_000))
    register_publisher(client, topic, type_name, latch, queue_size)


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
