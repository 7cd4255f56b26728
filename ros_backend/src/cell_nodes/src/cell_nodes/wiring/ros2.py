"""The nodes' wiring on ROS 2 (rclpy): one node, node parameters, transient local for what ROS 1 latched.

Threads as rospy has them: a single-threaded executor only moves data (rclpy's MultiThreadedExecutor costs a core
by itself: docs/rosbridge.md); each subscription's callbacks run on a thread of its own, in order, from a queue of
its queue_size (the oldest dropped, as rospy does), each service request on a thread of its own, each timer on a
thread of its own. So a callback may block (call a service, wait for a move) without stalling the node.

Signals: SIGINT and SIGTERM shut the node down (ok() turns False, spin and sleep return), as a rospy node ends on
both; rclpy's own handler is not installed (it would raise KeyboardInterrupt in whatever the main thread does).
"""
from __future__ import annotations

import collections
import signal
import threading
import time
from typing import Any, Callable, Dict, List, Optional

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.task import Future
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from .api import Closer, ServiceError


def qos(depth: int, latch: bool, best_effort: bool = False) -> QoSProfile:
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=max(1, depth),
                      reliability=ReliabilityPolicy.BEST_EFFORT if best_effort else ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latch else DurabilityPolicy.VOLATILE)


class _Publisher:
    def __init__(self, wiring: "Ros2Wiring", pub: Any) -> None:
        self._wiring, self.pub = wiring, pub

    def publish(self, msg: Any) -> bool:
        if not self._wiring.ok():
            return False
        try:
            self.pub.publish(msg)
            return True
        except Exception:  # rclpy raises on a context already shut down: the node is stopping
            if not self._wiring.ok():
                return False
            raise

    def subscriber_count(self) -> int:
        return self.pub.get_subscription_count()

    def close(self) -> None:
        self._wiring.node.destroy_publisher(self.pub)


# A request to a server this process has not had an answer from yet can be lost: the client sees the server in the
# graph before DDS matched the request and response endpoints both ways (Fast DDS resends lost discovery data on its
# heartbeat, seconds later), and rmw drops a response to a reader the server has not matched. Measured here: ~1 in 7
# first calls after a server restart never answered. So until a server (by its response writer's id) has answered
# once, a call is sent again after FIRST_ANSWER_S without an answer (at least once, for that first call only; later
# calls are sent once). Our services' first calls are reads or idempotent sets (a mode, parameter values).
FIRST_ANSWER_S = 1.0
_answered: set = set()
_answered_lock = threading.Lock()


def _servers(node: Node, service: str) -> List[bytes]:
    topic = f"rr{service if service.startswith('/') else '/' + service}Reply"
    return [bytes(i.endpoint_gid) for i in node.get_publishers_info_by_topic(topic, no_mangle=True)]


def call(node: Node, client: Any, service: str, request: Any, timeout: float) -> Any:
    """Call through an rclpy client, waiting at most `timeout` s; the response, or ServiceError (see above)."""
    deadline = time.monotonic() + timeout
    if not client.wait_for_service(timeout_sec=timeout):
        raise ServiceError(f"service {service} is not available")
    servers = _servers(node, service)
    with _answered_lock:
        known = bool(servers) and all(s in _answered for s in servers)
    while True:
        done = threading.Event()
        future = client.call_async(request)
        future.add_done_callback(lambda _f: done.set())
        left = max(0.0, deadline - time.monotonic())
        if done.wait(left if known else min(left, FIRST_ANSWER_S)):
            break
        future.cancel()
        if known or time.monotonic() >= deadline:
            raise ServiceError(f"service {service} did not answer within {timeout:g} s")
        known = True  # the one more try runs until the deadline
    if future.exception() is not None:
        raise ServiceError(f"service {service} failed: {future.exception()}")
    with _answered_lock:
        _answered.update(servers)
    return future.result()


class _Client:
    def __init__(self, wiring: "Ros2Wiring", name: str, srv_cls: type) -> None:
        self._wiring, self.name, self.srv_cls = wiring, name, srv_cls
        self.client = wiring.node.create_client(srv_cls, name, callback_group=wiring.group)

    def wait(self, timeout: float) -> bool:
        return bool(self.client.wait_for_service(timeout_sec=timeout))

    def __call__(self, request: Any = None, timeout: float = 10.0, **fields: Any) -> Any:
        if request is None:
            request = self.srv_cls.Request(**fields)
        return call(self._wiring.node, self.client, self.name, request, timeout)

    def close(self) -> None:
        self._wiring.node.destroy_client(self.client)


class _Lane:
    """A thread that runs `run(item)` for each item put, in order; at most `size` waiting (the oldest dropped)."""

    def __init__(self, name: str, size: int, run: Callable[[Any], None]) -> None:
        self._items: collections.deque = collections.deque(maxlen=max(1, size))
        self._ready = threading.Condition()
        self._closed = False
        self._run = run
        threading.Thread(target=self._loop, name=name, daemon=True).start()

    def put(self, item: Any) -> None:
        with self._ready:
            self._items.append(item)
            self._ready.notify()

    def close(self) -> None:
        with self._ready:
            self._closed = True
            self._ready.notify()

    def _loop(self) -> None:
        while True:
            with self._ready:
                while not self._items and not self._closed:
                    self._ready.wait()
                if self._closed:
                    return
                item = self._items.popleft()
            try:
                self._run(item)
            except Exception:  # as rospy: the callback's error is logged, the node goes on
                import traceback
                traceback.print_exc()


class Ros2Wiring:
    ros_version = 2

    def __init__(self, name: str, argv: Optional[List[str]] = None, anonymous: bool = False,
                 disable_signals: bool = False) -> None:
        if not rclpy.ok():
            rclpy.init(args=argv, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
        if anonymous:
            name = f"{name}_{id(self) & 0xffffff:x}"
        self.node = Node(name, allow_undeclared_parameters=True,
                         automatically_declare_parameters_from_overrides=True)
        ns = self.node.get_namespace().rstrip("/")
        self.name = f"{ns}/{self.node.get_name()}"
        self.group = ReentrantCallbackGroup()
        self._executor = SingleThreadedExecutor()
        self._executor.add_node(self.node)
        self._spinner: Optional[threading.Thread] = None
        self._senders: Dict[bytes, str] = {}
        self._stopping = threading.Event()
        self._closed = False
        if not disable_signals:
            for sig in (signal.SIGINT, signal.SIGTERM):
                signal.signal(sig, lambda number, _frame: self.shutdown(signal.Signals(number).name))
        # Callbacks run from the start (a service may be called before spin()), as rospy's do.
        self._spinner = threading.Thread(target=self._spin, name="rclpy executor", daemon=True)
        self._spinner.start()

    def _spin(self) -> None:
        try:
            self._executor.spin()
        except (ExternalShutdownException, KeyboardInterrupt):
            pass
        finally:
            self._stopping.set()

    def param(self, name: str, default: Any) -> Any:
        if self.node.has_parameter(name):
            value = self.node.get_parameter(name).value
            return default if value is None else value
        return default

    def publisher(self, topic: str, msg_cls: type, latch: bool = False, queue_size: int = 10) -> _Publisher:
        return _Publisher(self, self.node.create_publisher(msg_cls, topic, qos(queue_size, latch)))

    def _sender(self, topic: str, info: Any) -> str:
        gid = info.get("publisher_gid") if isinstance(info, dict) else None
        data = bytes(gid["data"]) if isinstance(gid, dict) and "data" in gid else None
        if data is None:
            return ""
        name = self._senders.get(data)
        if name is None:
            for endpoint in self.node.get_publishers_info_by_topic(topic):
                if bytes(endpoint.endpoint_gid)[:len(data)] == data[:len(bytes(endpoint.endpoint_gid))]:
                    ns = endpoint.node_namespace.rstrip("/")
                    name = self._senders[data] = f"{ns}/{endpoint.node_name}"
                    break
        return name or ""

    def subscribe(self, topic: str, msg_cls: type, callback: Callable[[Any, str], None], queue_size: int = 10,
                  latched: bool = False, newest_only: bool = False) -> Closer:
        def on_message(msg: Any, info: Any) -> None:
            callback(msg, self._sender(topic, info))

        depth = 1 if newest_only else queue_size
        lane = _Lane(f"sub {topic}", depth, lambda item: callback(item[0], self._sender(topic, item[1])))
        sub = self.node.create_subscription(msg_cls, topic, lambda msg, info: lane.put((msg, info)),
                                            qos(depth, latched, best_effort=newest_only), callback_group=self.group)

        def close() -> None:
            self.node.destroy_subscription(sub)
            lane.close()
        return Closer(close)

    def subscribers(self, topic: str) -> list[str]:
        return sorted(f"{i.node_namespace.rstrip('/')}/{i.node_name}"
                      for i in self.node.get_subscriptions_info_by_topic(topic))

    def service(self, name: str, srv_cls: type, handler: Callable[[Any], Any]) -> Closer:
        executor = self._executor

        def answer(request: Any, done: Future) -> None:
            try:
                done.set_result(handler(request))
            except Exception as exc:  # the caller gets a default response (ROS 2 has no error reply)
                self.error("service %s failed: %s", name, exc)
                done.set_result(srv_cls.Response())

        async def on_request(request: Any, _response: Any) -> Any:
            done = Future(executor=executor)
            done.add_done_callback(lambda _f: None)  # set_result then wakes the executor (a task is scheduled)
            threading.Thread(target=answer, args=(request, done), name=f"serve {name}", daemon=True).start()
            return await done

        svc = self.node.create_service(srv_cls, name, on_request, callback_group=self.group)
        return Closer(lambda: self.node.destroy_service(svc))

    def client(self, name: str, srv_cls: type) -> _Client:
        return _Client(self, name, srv_cls)

    def request(self, srv_cls: type, **fields: Any) -> Any:
        return srv_cls.Request(**fields)

    def response(self, srv_cls: type, **fields: Any) -> Any:
        return srv_cls.Response(**fields)

    def timer(self, period: float, callback: Callable[[], None]) -> Closer:
        lane = _Lane(f"timer {period:g} s", 1, lambda _item: callback())
        timer = self.node.create_timer(period, lambda: lane.put(None), callback_group=self.group)

        def close() -> None:
            self.node.destroy_timer(timer)
            lane.close()
        return Closer(close)

    def now(self) -> float:
        return self.node.get_clock().now().nanoseconds / 1e9

    def stamp(self, seconds: float) -> Any:
        from builtin_interfaces.msg import Time
        ns = int(round(seconds * 1e9))
        return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)

    def seconds(self, stamp: Any) -> float:
        return stamp.sec + stamp.nanosec / 1e9

    def info(self, text: str, *args: Any) -> None:
        self.node.get_logger().info(text % args if args else text)

    def warn(self, text: str, *args: Any) -> None:
        self.node.get_logger().warning(text % args if args else text)

    def error(self, text: str, *args: Any) -> None:
        self.node.get_logger().error(text % args if args else text)

    def ok(self) -> bool:
        return rclpy.ok() and not self._stopping.is_set()

    def sleep(self, seconds: float) -> bool:
        self._stopping.wait(seconds)
        return self.ok()

    def wait_for_message(self, topic: str, msg_cls: type, timeout: float) -> Any:
        got: List[Any] = []
        heard = threading.Event()
        sub = self.subscribe(topic, msg_cls, lambda msg, _sender: (got.append(msg), heard.set()), queue_size=1)
        try:
            deadline = time.monotonic() + timeout
            while not heard.is_set() and self.ok() and time.monotonic() < deadline:
                heard.wait(min(0.1, max(0.0, deadline - time.monotonic())))
            return got[0] if got else None
        finally:
            sub.close()

    def spin(self) -> None:
        try:
            while self.ok():
                self._stopping.wait(0.2)
        except KeyboardInterrupt:
            pass
        finally:
            self.shutdown("spin ended")

    def shutdown(self, reason: str = "") -> None:
        if self._stopping.is_set() and self._closed:
            return
        self._stopping.set()
        self._executor.shutdown(timeout_sec=1.0)
        if self._spinner is not None and self._spinner is not threading.current_thread():
            self._spinner.join(5)  # out of rclpy before the node goes (else a C++ abort at exit)
        if not self._closed:
            self._closed = True
            # The node's endpoints leave the graph now (peers hear it at once), not when DDS's lease runs out.
            self.node.destroy_node()
        if rclpy.ok():
            rclpy.try_shutdown()
