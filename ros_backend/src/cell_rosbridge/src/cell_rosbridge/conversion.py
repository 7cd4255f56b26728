"""ROS message <-> plain Python structures (the rosbridge v2 wire form), for either generation.

The walker is one; what a generation's message classes look like is in types_ros1 / types_ros2.

Two output flavours share one walker:
- JSON form: uint8[]/char[] as base64 text, NaN/inf floats as None (JSON has no NaN; rosbridge maps them to null).
- CBOR form: uint8[]/char[] as raw bytes, other numeric arrays as RFC 8746 typed-array tags, floats kept exact.
Incoming dicts are checked field by field so a bad message yields an error naming the field, never a
half-built message published on ROS.
"""
from __future__ import annotations

import base64
import math
import struct
from functools import lru_cache
from typing import Any, Dict, List, Optional, Tuple

from .generation import ROS_VERSION

if ROS_VERSION == 2:
    from . import types_ros2 as _types
else:
    from . import types_ros1 as _types  # type: ignore[no-redef]

try:  # cbor2 is optional for JSON-only use; tags are only needed for CBOR output
    from cbor2 import CBORTag
except ImportError:  # pragma: no cover
    CBORTag = None  # type: ignore

INT_RANGES: Dict[str, Tuple[int, int]] = {
    "int8": (-2**7, 2**7 - 1), "byte": (-2**7, 2**7 - 1),
    "uint8": (0, 2**8 - 1), "char": (0, 2**8 - 1),
    "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1),
    "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1),
}
FLOAT_TYPES = frozenset(("float32", "float64"))
TIME_TYPES = frozenset(("time", "duration"))
PRIMITIVES = frozenset(INT_RANGES) | FLOAT_TYPES | {"bool", "string"}
BYTE_ARRAY_BASES = frozenset(("uint8", "char"))

# RFC 8746 typed-array tags, little endian (what roslib's CBOR decoder understands).
_TYPED_ARRAY_TAGS: Dict[str, Tuple[int, str]] = {
    "int8": (72, "b"), "byte": (72, "b"), "uint16": (69, "H"), "int16": (77, "h"),
    "uint32": (70, "I"), "int32": (78, "i"), "uint64": (71, "Q"), "int64": (79, "q"),
    "float32": (85, "f"), "float64": (86, "d"),
}


class ConversionError(ValueError):
    """A message dict does not fit its ROS type; `path` names the offending field."""

    def __init__(self, path: str, reason: str) -> None:
        super().__init__(f"field '{path or '<root>'}': {reason}")
        self.path = path


class UnknownTypeError(ValueError):
    pass


_fields = _types.fields
type_name_of = _types.type_name
request_class = _types.request_class
response_class = _types.response_class


def normalize_type(type_name: str) -> str:
    """Accept 'pkg/msg/Type' (the ROS 2 spelling; also srv, action) as 'pkg/Type'."""
    parts = type_name.strip().split("/")
    if len(parts) == 3 and parts[1] in ("msg", "srv", "action"):
        return f"{parts[0]}/{parts[2]}"
    return type_name.strip()


def get_message_class(type_name: str) -> type:
    if not isinstance(type_name, str) or not type_name:
        raise UnknownTypeError(f"invalid message type {type_name!r}")
    type_name = normalize_type(type_name)
    try:
        cls = _types.load_message(type_name)
    except Exception as exc:  # roslib raises several kinds on bad names
        raise UnknownTypeError(f"unknown message type '{type_name}': {exc}") from exc
    if cls is None:
        raise UnknownTypeError(f"unknown message type '{type_name}'")
    return cls


def get_service_class(type_name: str) -> type:
    if not isinstance(type_name, str) or not type_name:
        raise UnknownTypeError(f"invalid service type {type_name!r}")
    type_name = normalize_type(type_name)
    try:
        cls = _types.load_service(type_name)
    except Exception as exc:
        raise UnknownTypeError(f"unknown service type '{type_name}': {exc}") from exc
    if cls is None:
        raise UnknownTypeError(f"unknown service type '{type_name}'")
    return cls


# ---------------------------------------------------------------- ROS -> dict

def _json_float(v: float) -> Optional[float]:
    return v if math.isfinite(v) else None


def msg_to_dict(msg: Any, cbor: bool = False) -> Dict[str, Any]:
    """Convert a genpy message to the rosbridge wire structure (JSON form, or CBOR form)."""
    out: Dict[str, Any] = {}
    for name, slot_type, base, is_array, _ in _fields(type(msg)):
        out[name] = _value_to_wire(getattr(msg, name), base, is_array, cbor)
    return out


def _value_to_wire(value: Any, base: str, is_array: bool, cbor: bool) -> Any:
    if is_array:
        if base in BYTE_ARRAY_BASES or (base == "byte" and ROS_VERSION == 2):  # ROS 2 octet: bytes too
            if value and isinstance(value, list) and isinstance(value[0], bytes):
                value = b"".join(value)
            raw = value if isinstance(value, (bytes, bytearray)) else bytes(value)  # array.array, numpy
            return bytes(raw) if cbor else base64.b64encode(raw).decode("ascii")
        if hasattr(value, "tolist"):  # rclpy's array.array and numpy arrays
            value = value.tolist()
        if base in FLOAT_TYPES:
            if cbor:
                return _typed_array(base, value)
            return [v if math.isfinite(v) else None for v in value]
        if base in INT_RANGES:
            return _typed_array(base, value) if cbor else list(value)
        if base in ("bool", "string"):
            return list(value)
        if base in TIME_TYPES:
            return [{"secs": v.secs, "nsecs": v.nsecs} for v in value]
        return [msg_to_dict(v, cbor) for v in value]
    if base in FLOAT_TYPES:
        return value if cbor else _json_float(value)
    if isinstance(value, bytes):  # a ROS 2 octet (`byte`): one byte, an int on the wire
        return value[0] if value else 0
    if base in PRIMITIVES:
        return value
    if base in TIME_TYPES:
        return {"secs": value.secs, "nsecs": value.nsecs}
    return msg_to_dict(value, cbor)


def _typed_array(base: str, values: Any) -> Any:
    tag, code = _TYPED_ARRAY_TAGS[base]
    n = len(values)
    if n == 0 or CBORTag is None:
        return list(values)
    return CBORTag(tag, struct.pack(f"<{n}{code}", *values))


# ---------------------------------------------------------------- dict -> ROS

def dict_to_msg(msg_cls: type, data: Any, path: str = "", stamp_now: bool = True,
                missing: Optional[List[str]] = None) -> Any:
    """Build a message of `msg_cls` from `data`; missing fields get defaults (listed in `missing`).

    Headers: an omitted header, or an omitted header.stamp, is filled with the current time (rosbridge
    spec); rospy's publisher fills header.seq.
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConversionError(path, f"expected an object for {type_name_of(msg_cls)}, got {type(data).__name__}")
    msg = msg_cls()
    plan = _fields(msg_cls)
    known = {f[0] for f in plan}
    for key in data:
        if key not in known:
            raise ConversionError(_join(path, str(key)), f"no such field in {type_name_of(msg_cls)}")
    for name, slot_type, base, is_array, length in plan:
        fpath = _join(path, name)
        if name not in data:
            if stamp_now and base == "std_msgs/Header" and not is_array:
                getattr(msg, name).stamp = _types.now()
            elif missing is not None:
                missing.append(fpath)
            continue
        value = data[name]
        if stamp_now and base == "std_msgs/Header" and not is_array and isinstance(value, dict) \
                and "stamp" not in value:
            header = dict_to_msg(msg_cls=_header_cls(), data=value, path=fpath, stamp_now=False)
            header.stamp = _types.now()
            setattr(msg, name, header)
            continue
        setattr(msg, name, _wire_to_value(value, slot_type, base, is_array, length, fpath, stamp_now, missing))
    return msg


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name


@lru_cache(maxsize=1)
def _header_cls() -> type:
    return get_message_class("std_msgs/Header")


def _wire_to_value(value: Any, slot_type: str, base: str, is_array: bool, length: Optional[int],
                   path: str, stamp_now: bool, missing: Optional[List[str]]) -> Any:
    if is_array:
        if base in BYTE_ARRAY_BASES or (base == "byte" and ROS_VERSION == 2):
            raw = _to_bytes(value, path)
            if length is not None and len(raw) != length:
                raise ConversionError(path, f"expected {length} bytes, got {len(raw)}")
            return _types.byte_array(base, raw, length) if ROS_VERSION == 2 else raw
        if CBORTag is not None and isinstance(value, CBORTag):
            value = _untag(value, path)
        if not isinstance(value, (list, tuple)):
            raise ConversionError(path, f"expected an array for {slot_type}, got {type(value).__name__}")
        if length is not None and len(value) != length:
            raise ConversionError(path, f"expected {length} elements, got {len(value)}")
        items = [_wire_to_value(v, base, base, False, None, f"{path}[{i}]", stamp_now, missing)
                 for i, v in enumerate(value)]
        return _types.number_array(base, items, length) if ROS_VERSION == 2 else items
    if base == "bool":
        if isinstance(value, bool):
            return value
        if isinstance(value, int) and value in (0, 1):
            return bool(value)
        raise ConversionError(path, f"expected bool, got {type(value).__name__}")
    if base == "byte" and ROS_VERSION == 2:  # octet: 0..255 on the wire, one bytes object in rclpy
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 255:
            raise ConversionError(path, f"expected a byte 0..255, got {value!r}")
        return bytes([value])
    if base in INT_RANGES:
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and value.is_integer():
                value = int(value)
            else:
                raise ConversionError(path, f"expected {base}, got {type(value).__name__}")
        lo, hi = INT_RANGES[base]
        if not lo <= value <= hi:
            raise ConversionError(path, f"{value} out of range for {base}")
        return value
    if base in FLOAT_TYPES:
        if value is None:  # null is how JSON carries NaN/inf out of rosbridge; accept it back as NaN
            return float("nan")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConversionError(path, f"expected {base}, got {type(value).__name__}")
        return float(value)
    if base == "string":
        if not isinstance(value, str):
            raise ConversionError(path, f"expected string, got {type(value).__name__}")
        return value
    if base in TIME_TYPES:
        return _to_time(value, base, path)
    try:
        cls = get_message_class(base)
    except UnknownTypeError as exc:
        raise ConversionError(path, str(exc)) from exc
    return dict_to_msg(cls, value, path, stamp_now, missing)


def _to_bytes(value: Any, path: str) -> bytes:
    if isinstance(value, (bytes, bytearray)):
        return bytes(value)
    if isinstance(value, str):
        try:
            return base64.b64decode(value, validate=True)
        except Exception as exc:
            raise ConversionError(path, "invalid base64 for byte array") from exc
    if CBORTag is not None and isinstance(value, CBORTag) and isinstance(value.value, bytes):
        return value.value
    if isinstance(value, (list, tuple)):
        try:
            return bytes(value)
        except (TypeError, ValueError) as exc:
            raise ConversionError(path, "byte array elements must be integers 0..255") from exc
    raise ConversionError(path, f"expected bytes, base64 string or int list, got {type(value).__name__}")


def _untag(tag: Any, path: str) -> List[Any]:
    for base, (num, code) in _TYPED_ARRAY_TAGS.items():
        if num == tag.tag and isinstance(tag.value, bytes):
            size = struct.calcsize(code)
            if len(tag.value) % size:
                raise ConversionError(path, "typed array length is not a multiple of its element size")
            return list(struct.unpack(f"<{len(tag.value) // size}{code}", tag.value))
    raise ConversionError(path, f"unsupported CBOR tag {tag.tag}")


def _to_time(value: Any, base: str, path: str) -> Any:
    if isinstance(value, dict):
        secs = value.get("secs", value.get("sec", 0))
        nsecs = value.get("nsecs", value.get("nanosec", 0))
        extra = set(value) - {"secs", "nsecs", "sec", "nanosec"}
        if extra:
            raise ConversionError(path, f"unexpected keys {sorted(extra)} in {base}")
        for v in (secs, nsecs):
            if isinstance(v, bool) or not isinstance(v, int):
                raise ConversionError(path, f"{base} secs/nsecs must be integers")
        if base == "time" and (secs < 0 or nsecs < 0 or secs > 2**32 - 1):
            raise ConversionError(path, f"{base} out of range")
        if not (-2**31 <= secs <= 2**32 - 1):
            raise ConversionError(path, f"{base} out of range")
        return _types.make_time(base, secs, nsecs)
    if value == "now" and base == "time":
        return _types.now()
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return _types.time_from_sec(base, value)
    raise ConversionError(path, f"expected {{secs, nsecs}} for {base}, got {type(value).__name__}")


def args_to_request(req_cls: type, args: Any) -> Any:
    """Service args may be an object (by field name) or a list (positional, the spec's form)."""
    if args is None:
        args = {}
    if isinstance(args, (list, tuple)):
        names = [f[0] for f in _fields(req_cls)]
        if len(args) > len(names):
            raise ConversionError("args", f"{len(args)} positional args for {len(names)} fields")
        args = dict(zip(names, args))
    return dict_to_msg(req_cls, args, path="")


def serialize(msg: Any) -> bytes:
    """The generation's wire bytes of a message (for cbor-raw): ROS 1 serialization or CDR."""
    return _types.serialize(msg)
