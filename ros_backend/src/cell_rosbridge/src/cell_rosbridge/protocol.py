"""The rosbridge v2 dispatcher: one `Client` per connection, no sockets in sight.

A transport feeds frames to `Client.incoming` and drains `Client.outbox`; everything else (ops, status
errors, fragments, resource release) lives here and in capabilities/, so it is testable without a server.
"""
from __future__ import annotations

import itertools
import logging
import re
import threading
from dataclasses import dataclass, field
from typing import Any, Dict, Hashable, List, Optional

from . import encoding
from .conversion import ConversionError, UnknownTypeError
from .encoding import Frame
from .op_base import LEVELS, Finalizer, Handler, ProtocolError
from .outbox import CONTROL, ClientOutbox
from .plumbing import PublisherRegistry, ServiceCallError, TopicError, TopicHub

log = logging.getLogger("rosbridge")


@dataclass
class BridgeConfig:
    max_message_size: int = 10_000_000  # largest accepted incoming message (frame or reassembled fragments)
    max_client_buffer: int = 64 * 1024 * 1024  # queued outgoing bytes before a client is disconnected
    default_queue_length: int = 1000  # bound of a subscription lane when queue_length is 0
    service_request_timeout: float = 30.0  # how long a ROS caller waits for a browser-served service
    max_pending_calls: int = 32  # concurrent call_service per client
    max_fragment_buffers: int = 16  # concurrent incomplete incoming fragmented messages per client
    # A new publisher keeps what it sends in its first seconds for ROS subscribers still connecting.
    publisher_replay_window: float = 1.0  # seconds after the publisher is created; 0 disables
    publisher_replay_max: int = 100  # messages kept per new publisher (oldest dropped first)
    # A publisher no client holds stays registered this long (rosbridge_suite's unregister_timeout); 0: at once.
    unregister_timeout: float = 10.0

    # What a node parameter of the same name sets (ROS 1: private ~name; ROS 2: node parameter name).
    TUNABLE = ("max_message_size", "max_client_buffer", "default_queue_length", "service_request_timeout",
               "publisher_replay_window", "publisher_replay_max", "unregister_timeout")


@dataclass
class BridgeContext:
    """What all clients of one server share, including the ops they can use.

    The dispatcher knows no op itself: whoever builds the server registers them (node.build_context,
    capabilities.register_all), so this module never imports the capabilities.
    """
    config: BridgeConfig = field(default_factory=BridgeConfig)
    hub: TopicHub = field(default_factory=TopicHub)
    publishers: Optional[PublisherRegistry] = None
    services: Dict[str, Any] = field(default_factory=dict)  # service name -> AdvertisedService
    lock: threading.RLock = field(default_factory=threading.RLock)
    handlers: Dict[str, Handler] = field(default_factory=dict)  # op -> handler
    finalizers: List[Finalizer] = field(default_factory=list)  # release a finished client's resources

    def __post_init__(self) -> None:
        if self.publishers is None:
            self.publishers = PublisherRegistry(self.hub, self.config.publisher_replay_window,
                                                self.config.publisher_replay_max, self.config.unregister_timeout)

    def register(self, op: str, handler: Handler) -> None:
        self.handlers[op] = handler

    def add_finalizer(self, finalizer: Finalizer) -> None:
        self.finalizers.append(finalizer)


_ids = itertools.count(1)
_OP_RE = re.compile(r'"op"\s*:\s*"([^"]{1,64})"')
_ID_RE = re.compile(r'"id"\s*:\s*("(?:[^"\\]|\\.){0,200}"|-?\d{1,20})')


class Client:
    """Protocol state of one connection."""

    def __init__(self, context: BridgeContext, outbox: ClientOutbox, name: str = "") -> None:
        self.id = next(_ids)
        self.name = name or f"client{self.id}"
        self.context = context
        self.outbox = outbox
        self.handlers: Dict[str, Handler] = context.handlers  # shared, registered by the builder
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
        for fin in self.context.finalizers:
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
