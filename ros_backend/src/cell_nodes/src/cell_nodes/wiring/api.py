"""The interface every node's wiring is written against (implemented by ros1.py and ros2.py)."""
from __future__ import annotations

from typing import Any, Callable, Optional, Protocol


class Handle(Protocol):
    def close(self) -> None:
        """End it (unsubscribe, withdraw the service, stop the timer); idempotent."""


class Closer:
    """A Handle that runs `close` once."""

    def __init__(self, close: Callable[[], None]) -> None:
        self._close: Optional[Callable[[], None]] = close

    def close(self) -> None:
        close, self._close = self._close, None
        if close is not None:
            close()


class Publisher(Protocol):
    def publish(self, msg: Any) -> bool:
        """Publish; False (and nothing raised) when the node is stopping."""

    def subscriber_count(self) -> int:
        """How many subscriptions this publisher has now (nobody watching: work can be skipped)."""

    def close(self) -> None: ...


class ServiceClient(Protocol):
    def wait(self, timeout: float) -> bool:
        """Whether the service is there within `timeout` seconds."""

    def __call__(self, request: Any = None, timeout: float = 10.0, **fields: Any) -> Any:
        """Call with a request (or its fields); the response, or ServiceError."""

    def close(self) -> None: ...


class ServiceError(RuntimeError):
    """A service call that failed: no such service, no answer in time, or the server's error."""


class Wiring(Protocol):
    """One ROS node of either generation, as our nodes use it."""

    name: str  # the node's fully qualified name, e.g. /operation_mode
    ros_version: int

    def param(self, name: str, default: Any) -> Any:
        """The node's own parameter `name` (ROS 1: private ~name; ROS 2: node parameter), else `default`."""

    def publisher(self, topic: str, msg_cls: type, latch: bool = False, queue_size: int = 10) -> Publisher:
        """latch: a late subscriber gets the last message (ROS 1 latching; ROS 2 transient local)."""

    def subscribe(self, topic: str, msg_cls: type, callback: Callable[[Any, str], None], queue_size: int = 10,
                  latched: bool = False, newest_only: bool = False) -> Handle:
        """callback(msg, sender): sender is the publishing node's name ('' where unknown). latched: hear the last
        message of latching publishers on joining. On ROS 1 a subscriber always does; on ROS 2 it asks for transient
        local, which only transient-local (latching) publishers offer: DDS leaves a latched subscription deaf to a
        volatile publisher. Leave it False to hear every publisher. newest_only: a stream where only the newest
        message matters (camera frames): a queue of one that a slow callback skips through (ROS 1: with a buffer
        for a whole frame; ROS 2: best effort, which hears reliable and best-effort publishers alike)."""

    def subscribers(self, topic: str) -> list[str]:
        """The names of the nodes subscribed to `topic` now, sorted (the graph's view)."""

    def service(self, name: str, srv_cls: type, handler: Callable[[Any], Any]) -> Handle:
        """handler(request) -> response (see `response`)."""

    def client(self, name: str, srv_cls: type) -> ServiceClient: ...

    def request(self, srv_cls: type, **fields: Any) -> Any: ...

    def response(self, srv_cls: type, **fields: Any) -> Any: ...

    def timer(self, period: float, callback: Callable[[], None]) -> Handle: ...

    def now(self) -> float:
        """Seconds since the epoch, as the node's clock has it."""

    def stamp(self, seconds: float) -> Any:
        """A time field's value for `seconds` (rospy.Time or builtin_interfaces/Time)."""

    def seconds(self, stamp: Any) -> float: ...

    def info(self, text: str, *args: Any) -> None: ...

    def warn(self, text: str, *args: Any) -> None: ...

    def error(self, text: str, *args: Any) -> None: ...

    def ok(self) -> bool:
        """False once the node is shutting down."""

    def sleep(self, seconds: float) -> bool:
        """Wait `seconds`, or less if the node shuts down meanwhile; whether it still runs."""

    def wait_for_message(self, topic: str, msg_cls: type, timeout: float) -> Any:
        """The next message on `topic` (subscribed only while waiting), or None after `timeout` or at shutdown."""

    def spin(self) -> None:
        """Serve callbacks until the node is shut down (SIGINT, SIGTERM or shutdown())."""

    def shutdown(self, reason: str = "") -> None: ...


