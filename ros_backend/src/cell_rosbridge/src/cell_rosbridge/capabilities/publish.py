"""publish: convert the client's dict to the topic's ROS type and publish it."""
from __future__ import annotations

from typing import Any, Dict, List

from .. import conversion
from ..op_base import check, ensure_publisher, require
from ..plumbing import resolve_topic


def publish(client: Any, msg: Dict[str, Any]) -> None:
    topic = resolve_topic(require(msg, "topic", str))
    body = require(msg, "msg", dict)
    latch = check(msg, "latch", bool, False)
    pub = ensure_publisher(client, topic, latch)
    missing: List[str] = []
    ros_msg = conversion.dict_to_msg(pub.msg_cls, body, missing=missing)
    if missing:  # spec: a subset of the type is published with defaults, plus a warning
        client.status("warning", f"fields defaulted: {', '.join(missing[:20])}", op="publish",
                      msg_id=msg.get("id"))
    pub.publish(ros_msg)  # through the replay buffer: subscribers may still be connecting
