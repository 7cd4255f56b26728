"""ROS 2 (rosidl) message classes as conversion.py walks them: their field types in ROS 1 spelling.

rclpy names a field's type 'double', 'sequence<int32>', 'sequence<double, 5>', 'string<=10', 'uint8[16]' or
'pkg/Type'; the walker knows 'float64', 'int32[]' and 'pkg/Type'. Time and Duration are plain messages here
(builtin_interfaces, {sec, nanosec} on the wire, as rosbridge_suite's ROS 2 server sends them).
"""
from __future__ import annotations

import importlib
import re
import time
from functools import lru_cache
from typing import Any, Optional, Tuple

Field = Tuple[str, str, str, bool, Optional[int]]
_BASES = {"double": "float64", "float": "float32", "boolean": "bool", "octet": "byte", "wstring": "string",
          "long double": "float64"}
_SEQUENCE = re.compile(r"^sequence<(.+?)(?:,\s*\d+)?>$")
_FIXED = re.compile(r"^(.+)\[(\d+)\]$")
_BOUNDED_STRING = re.compile(r"^(w?string)<=\d+$")


def _base(name: str) -> str:
    m = _BOUNDED_STRING.match(name)
    if m:
        name = m.group(1)
    return _BASES.get(name, name)


def split_type(ros2_type: str) -> Tuple[str, bool, Optional[int]]:
    """'sequence<double>' -> ('float64', True, None); 'uint8[16]' -> ('uint8', True, 16); 'pkg/T' -> ('pkg/T', False, None)."""
    m = _SEQUENCE.match(ros2_type)
    if m:
        return _base(m.group(1)), True, None
    m = _FIXED.match(ros2_type)
    if m:
        return _base(m.group(1)), True, int(m.group(2))
    return _base(ros2_type), False, None


@lru_cache(maxsize=None)
def fields(msg_cls: type) -> Tuple[Field, ...]:
    out = []
    for name, ros2_type in msg_cls.get_fields_and_field_types().items():
        base, is_array, length = split_type(ros2_type)
        slot = f"{base}[{length if length is not None else ''}]" if is_array else base
        out.append((name, slot, base, is_array, length))
    return tuple(out)


def type_name(msg_cls: type) -> str:
    module = msg_cls.__module__.split(".")  # pkg.msg._type
    return f"{module[0]}/{msg_cls.__name__}"


def _load(type_name: str, kinds: Tuple[str, ...]) -> Optional[type]:
    parts = type_name.split("/")
    if len(parts) == 3:
        kinds = (parts[1],)
        parts = [parts[0], parts[2]]
    if len(parts) != 2 or not all(re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", p) for p in parts):
        raise ValueError(f"not a type name: {type_name!r}")
    for kind in kinds:
        try:
            module = importlib.import_module(f"{parts[0]}.{kind}")
        except ImportError:
            continue
        cls = getattr(module, parts[1], None)
        if isinstance(cls, type):
            return cls
    return None


def load_message(type_name: str) -> Optional[type]:
    return _load(type_name, ("msg",))


def load_service(type_name: str) -> Optional[type]:
    return _load(type_name, ("srv",))


def load_action(type_name: str) -> Optional[type]:
    return _load(type_name, ("action",))


def request_class(srv_cls: type) -> type:
    return srv_cls.Request


def response_class(srv_cls: type) -> type:
    return srv_cls.Response


def now() -> Any:
    from builtin_interfaces.msg import Time
    ns = time.time_ns()
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def make_time(base: str, secs: int, nsecs: int) -> Any:
    raise ValueError(f"ROS 2 has no primitive {base}")


def time_from_sec(base: str, value: float) -> Any:
    raise ValueError(f"ROS 2 has no primitive {base}")


def serialize(msg: Any) -> bytes:
    """CDR bytes of a message (for cbor-raw), as rclpy serializes it."""
    from rclpy.serialization import serialize_message
    return serialize_message(msg)


_ARRAY_CODES = {"int8": "b", "uint8": "B", "char": "B", "int16": "h", "uint16": "H", "int32": "i", "uint32": "I",
                "int64": "q", "uint64": "Q", "float32": "f", "float64": "d"}


def byte_array(base: str, raw: bytes, length: Optional[int]) -> Any:
    """What rclpy's setter takes at once for a byte field (array.array; a bytes object is checked int by int)."""
    if base == "byte":  # octet: a list of 1-byte bytes objects
        return [raw[i:i + 1] for i in range(len(raw))]
    if length is not None:
        import numpy
        return numpy.frombuffer(raw, dtype=numpy.uint8).copy()
    import array
    return array.array("B", raw)


def number_array(base: str, items: list, length: Optional[int]) -> Any:
    """A numeric sequence as rclpy stores it (array.array, or numpy for a fixed length); others as lists."""
    code = _ARRAY_CODES.get(base)
    if code is None:
        return items
    if length is not None:
        import numpy
        return numpy.array(items, dtype=numpy.dtype(code))
    import array
    return array.array(code, items)
