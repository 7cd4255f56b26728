"""ROS 1 (genpy) message classes as conversion.py walks them."""
from __future__ import annotations

import io
from functools import lru_cache
from typing import Any, Optional, Tuple

import genpy
import roslib.message
import rospy

Field = Tuple[str, str, str, bool, Optional[int]]


def split_array_type(slot_type: str) -> Tuple[str, bool, Optional[int]]:
    """'float64[6]' -> ('float64', True, 6); 'string' -> ('string', False, None)."""
    if not slot_type.endswith("]"):
        return slot_type, False, None
    base, _, rest = slot_type.partition("[")
    size = rest[:-1]
    return base, True, int(size) if size else None


@lru_cache(maxsize=None)
def fields(msg_cls: type) -> Tuple[Field, ...]:
    """Per-type field plan, computed once (name, full type, base type, is_array, fixed length)."""
    out = []
    for name, slot_type in zip(msg_cls.__slots__, msg_cls._slot_types):
        base, is_array, length = split_array_type(slot_type)
        out.append((name, slot_type, base, is_array, length))
    return tuple(out)


def type_name(msg_cls: type) -> str:
    return msg_cls._type


def load_message(type_name: str) -> Optional[type]:
    return roslib.message.get_message_class(type_name, reload_on_error=False)


def load_service(type_name: str) -> Optional[type]:
    return roslib.message.get_service_class(type_name, reload_on_error=False)


def request_class(srv_cls: type) -> type:
    return srv_cls._request_class


def response_class(srv_cls: type) -> type:
    return srv_cls._response_class


def now() -> Any:
    """A header stamp of the current time."""
    return rospy.Time.now() if rospy.core.is_initialized() else genpy.Time()


def make_time(base: str, secs: int, nsecs: int) -> Any:
    return (genpy.Time if base == "time" else genpy.Duration)(secs, nsecs)


def time_from_sec(base: str, value: float) -> Any:
    return (genpy.Time if base == "time" else genpy.Duration).from_sec(value)


def serialize(msg: Any) -> bytes:
    """ROS 1 wire bytes of a message (for cbor-raw)."""
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()
