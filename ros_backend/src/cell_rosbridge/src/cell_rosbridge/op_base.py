"""What every capability (op handler) shares: request field checks, the ProtocolError, constants, and the
client's bookkeeping of the publishers it holds.

Capabilities import from here (and from conversion / plumbing), never from protocol.py or from each
other, so the dispatcher can be wired up from outside (node.build_context) without an import circle.
"""
from __future__ import annotations

import math
from typing import Any, Callable, Dict, Optional, Tuple


LEVELS: Dict[str, int] = {"info": 0, "warning": 1, "error": 2, "none": 3}
COMPRESSIONS: Tuple[str, ...] = ("none", "png", "cbor", "cbor-raw")

# The client is protocol.Client; typed as Any here because this module must not import protocol.
Handler = Callable[[Any, Dict[str, Any]], None]
Finalizer = Callable[[Any], None]


class ProtocolError(ValueError):
    """A request the client got wrong; reported as a status error naming op and id."""


def require(msg: Dict[str, Any], name: str, kind: type | Tuple[type, ...], what: str = "") -> Any:
    if name not in msg:
        raise ProtocolError(f"missing field '{name}'")
    return check(msg, name, kind, None)


def check(msg: Dict[str, Any], name: str, kind: type | Tuple[type, ...], default: Any) -> Any:
    """Optional field with a type check (bool is not accepted where a number is meant)."""
    value = msg.get(name, default)
    if value is None:
        return default
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if isinstance(value, bool) and bool not in kinds:
        raise ProtocolError(f"field '{name}' must be {'/'.join(k.__name__ for k in kinds)}, got bool")
    if not isinstance(value, kinds):
        raise ProtocolError(f"field '{name}' must be {'/'.join(k.__name__ for k in kinds)}, "
                            f"got {type(value).__name__}")
    return value


def number(msg: Dict[str, Any], name: str, default: Optional[float], minimum: float = 0.0,
           maximum: float = 1e9) -> Any:
    """Optional finite number field within [minimum, maximum] (JSON/CBOR can carry NaN, inf, 1e308)."""
    value = check(msg, name, (int, float), default)
    if value is None:
        return None
    if not math.isfinite(value) or not minimum <= value <= maximum:
        raise ProtocolError(f"field '{name}' must be a number in [{minimum:g}, {maximum:g}], got {value!r}")
    return value


def register_publisher(client: Any, topic: str, type_name: Optional[str], latch: bool,
                       queue_size: int) -> Any:
    """Take a reference on the shared publisher of `topic` for this client (advertise, implicit publish)."""
    with client.lock:
        pub = client.context.publishers.register(client.id, topic, type_name, latch, queue_size)
        client.advertised[topic] = client.advertised.get(topic, 0) + 1
        return pub


def ensure_publisher(client: Any, topic: str, latch: bool) -> Any:
    """publish without advertise: rosbridge registers implicitly when the topic's type is known."""
    pub = client.context.publishers.get(topic)
    if pub is not None and client.id in pub.clients:
        return pub
    return register_publisher(client, topic, None, latch, 100)
