"""The rosbridge v2 dispatcher: one `Client` per connection, no sockets in sight.

A transport feeds frames to `Client.incoming` and drains `Client.outbox`; everything else (ops, status
errors, fragments, resource release) lives here and in capabilities/, so it is testable without a server.
"""
from __future__ import annotations

import itertools
import math
import logging
import re
import threading
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Hashable, List, Optional, Tuple

from . import encoding
from .conversion import ConversionError, UnknownTypeError
from .encoding import Frame
from .outbox import CONTROL, ClientOutbox
from .ros_plumbing import PublisherRegistry, ServiceCallError, TopicError, TopicHub

log = logging.getLogger("rosbridge")

LEVELS = {"info": 0, "warning": 1, "error": 2, "none": 3}


class ProtocolError(ValueError):
    """A request the client got wrong; reported as a status error naming op and id."""


@dataclass
class BridgeConfig:
    max_message_size: int = 10_000_000  # largest accepted incoming message (frame or reassembled fragments)
    max_client_buffer: int = 64 * 1024 * 1024  # queued outgoing bytes before a client is disconnected
    default_queue_length: int = 1000  # bound of a subscription lane when queue_length is 0
    service_request_timeout: float = 30.0  # how long a ROS caller waits for a browser-served service
    max_pending_calls: int = 32  # concurrent call_service per client
    max_fragment_buffers: int = 16  # concurrent incomplete incoming fragmented messages per client


@dataclass
class BridgeContext:
    """What all clients of one server share."""
    config: BridgeConfig = field(default_factory=BridgeConfig)
    hub: TopicHub = field(default_factory=TopicHub)
    publishers: Optional[PublisherRegistry] = None
    services: Dict[str, Any] = field(default_factory=dict)  # service name -> AdvertisedService
    lock: threading.RLock = field(default_factory=threading.RLock)

    def __post_init__(self) -> None:
        if self.publishers is None:
            self.publishers = PublisherRegistry(self.hub)


_ids = itertools.count(1)
_OP_RE = re.compile(r'"op"\s*:\s*"([^"]{1,64})"')
_ID_RE = re.compile(r'"id"\s*:\s*("(?:[^"\\]|\\.){0,200}"|-?\d{1,20})')


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


class Client:
    """Protocol state of one connection."""

    def __init__(self, context: BridgeContext, outbox: ClientOutbox, name: str = "") -> None:
        from .capabilities import HANDLERS  # late import: capabilities import this module
        self.id = next(_ids)
        self.name = name or f"client{self.id}"
        self.context = context
        self.outbox = outbox
        self.handlers: Dict[str, Callable[["Client", Dict[str, Any]], None]] = HANDLERS
        self.status_level = LEVELS["error"]
        self.subscriptions: Dict[str, Any] = {}  # topic -> capabilities.subscribe.TopicSubscription
        self.advertised: Dict[str, int] = {}  # topic -> number of advertise calls (informational)
        self.services: Dict[str, Any] = {}  # service -> AdvertisedService
        self.fragments: Dict[Any, Dict[str, Any]] = {}
        self.pending_calls = 0
        self.lock = threading.RLock()
        self.finished = False

    # ------------------------------------------------------------------ incoming
    def incoming(self, frame: Frame) -> None:
        """Handle one frame from the client; never raises (errors become status messages)."""
        if self.finished:
            return
        size = len(frame)
        if size > self.context.config.max_message_size:
            head = frame[:512] if isinstance(frame, str) else bytes(frame[:512]).decode("latin-1")
            op = _OP_RE.search(head)
            mid = _ID_RE.search(head)
            self.status("error", f"message of {size} bytes exceeds max_message_size "
                                 f"{self.context.config.max_message_size}",
                        op=op.group(1) if op else "unknown", msg_id=_parse_id(mid.group(1)) if mid else None)
            return
        try:
            msg = encoding.decode_frame(frame)
        except encoding.DecodeError as exc:
            self.status("error", str(exc), op="unknown")
            return
        self.dispatch(msg, binary=not isinstance(frame, str))

    def dispatch(self, msg: Any, binary: bool = False) -> None:
        if not isinstance(msg, dict):
            self.status("error", f"a rosbridge message must be an object, got {type(msg).__name__}",
                        op="unknown")
            return
        op = msg.get("op")
        msg_id = msg.get("id")
        if not isinstance(msg_id, (str, int)) or isinstance(msg_id, bool):
            msg_id = None
        if not isinstance(op, str):
            self.status("error", "missing or non-string field 'op'", op="unknown", msg_id=msg_id)
            return
        handler = self.handlers.get(op)
        if handler is None:
            self.status("error", f"unknown operation '{op[:64]}'", op=op[:64], msg_id=msg_id)
            return
        try:
            handler(self, msg)
        except (ProtocolError, ConversionError, UnknownTypeError, TopicError, ServiceCallError) as exc:
            self.status("error", str(exc), op=op, msg_id=msg_id)
        except Exception as exc:  # a bug in one op must not kill the connection
            log.exception("%s: op %s failed", self.name, op)
            self.status("error", f"internal error: {type(exc).__name__}: {exc}", op=op, msg_id=msg_id)

    # ------------------------------------------------------------------ outgoing
    def send(self, obj: Dict[str, Any], cbor: bool = False, lane: Hashable = CONTROL) -> None:
        data: Frame = encoding.encode_cbor(obj) if cbor else encoding.encode_json(obj)
        self.outbox.push([data], len(data), lane)

    def send_encoded(self, obj: Dict[str, Any], compression: str = "none", fragment_size: int = 0,
                     frag_id: str = "", lane: Hashable = CONTROL) -> None:
        """Send a reply honouring the request's compression and fragment_size."""
        if compression in ("cbor", "cbor-raw"):
            self.send(obj, cbor=True, lane=lane)
            return
        frames = encoding.json_frames(encoding.encode_json(obj), compression, fragment_size,
                                      frag_id or f"{obj.get('op')}:{next(_ids)}")
        self.outbox.push(frames, sum(len(f) for f in frames), lane)

    def send_frames(self, frames: List[Frame], nbytes: int, lane: Hashable = CONTROL) -> None:
        self.outbox.push(frames, nbytes, lane)

    def status(self, level: str, text: str, op: str = "", msg_id: Any = None) -> None:
        if op:
            text = f"{op}: {text}"
        if level == "error":
            log.info("%s: %s%s", self.name, text, f" (id {msg_id})" if msg_id is not None else "")
        if LEVELS.get(level, 2) < self.status_level:
            return
        out: Dict[str, Any] = {"op": "status", "level": level, "msg": text}
        if msg_id is not None:
            out["id"] = msg_id
        self.send(out)

    # ------------------------------------------------------------------ teardown
    def finish(self) -> None:
        """Release every subscriber, publisher and service this client holds (idempotent)."""
        with self.lock:
            if self.finished:
                return
            self.finished = True
        from .capabilities import FINALIZERS
        for fin in FINALIZERS:
            try:
                fin(self)
            except Exception:
                log.exception("%s: cleanup failed", self.name)
        self.outbox.close()
        self.fragments.clear()


def _parse_id(raw: str) -> Any:
    if raw.startswith('"'):
        return raw[1:-1]
    return int(raw)
