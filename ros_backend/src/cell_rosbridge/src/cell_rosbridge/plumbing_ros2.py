"""The bridge's ROS 2 side (rclpy): shared subscribers and publishers (shared.py) on DDS, service calls and
services served for a client, the graph from rclpy's queries.

One rclpy node for the whole server (`start`), spun by a single-threaded executor on a thread of its own; the
WebSocket loop creates and destroys subscriptions, publishers and clients on it (rclpy allows that from any thread).
No callback blocks it: a served service's handler, which waits for the browser, runs on a thread of its own.
Single-threaded because rclpy's MultiThreadedExecutor costs a core by itself: measured here with 100 Hz arrays to
1-25 clients, it delivered 70 % at 106 % CPU and 0.7-1 s latency, the single-threaded one 100 % at 7-15 % CPU and
p95 1-3 ms (bench/rosbridge_bench.py).

QoS, as rosbridge_suite's ROS 2 server chooses it: a subscription is reliable unless every publisher of the topic
is best effort, and transient local when any publisher is (ROS 2's latching: a late subscriber gets the last
state). An advertise with latch=true makes a transient-local publisher.
"""
from __future__ import annotations

import logging
import threading
import time
from typing import Any, Callable, Dict, List, Optional

import rclpy
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import SingleThreadedExecutor
from rclpy.task import Future
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from cell_nodes.wiring.api import ServiceError
from cell_nodes.wiring.ros2 import call as ros2_call

from . import conversion, shared
from .shared import ActionGoalError, ServiceCallError, SharedMessage, TopicError

log = logging.getLogger("rosbridge")


class ServiceFailure(RuntimeError):
    """What a served service's handler raises to fail the ROS caller (ROS 2 has no error reply: see serve)."""


class _Runtime:
    node: Optional[Node] = None
    executor: Optional[SingleThreadedExecutor] = None
    thread: Optional[threading.Thread] = None
    group = ReentrantCallbackGroup()


_rt = _Runtime()


def start(name: str = "rosbridge_websocket") -> Node:
    """Create the server's node and spin it in the background (idempotent)."""
    if _rt.node is None:
        if not rclpy.ok():
            rclpy.init()
        _rt.node = Node(name)
        _rt.executor = SingleThreadedExecutor()
        _rt.executor.add_node(_rt.node)
        _rt.thread = threading.Thread(target=_rt.executor.spin, name="rclpy executor", daemon=True)
        _rt.thread.start()
    return _rt.node


def node() -> Node:
    if _rt.node is None:
        raise RuntimeError("plumbing_ros2.start() was not called")
    return _rt.node


def stop() -> None:
    with _clients_lock:
        for client in _action_clients.values():
            client.destroy()
        _action_clients.clear()
        for service_client in _service_clients.values():
            node().destroy_client(service_client)
        _service_clients.clear()
    if _rt.executor is not None:
        _rt.executor.shutdown(timeout_sec=2)
    if _rt.thread is not None:
        _rt.thread.join(5)  # the executor's thread out of rclpy before the node goes (else a C++ abort at exit)
    if _rt.node is not None:
        _rt.node.destroy_node()
    _rt.node = _rt.executor = _rt.thread = None
    if rclpy.ok():
        rclpy.shutdown()


def _short(type_name: str) -> str:
    return conversion.normalize_type(type_name)


def topic_types() -> Dict[str, str]:
    """topic -> type ('pkg/Type') for every topic in the graph (published or subscribed)."""
    return {name: _short(types[0]) for name, types in node().get_topic_names_and_types() if types}


def resolve_topic(name: Any) -> str:
    if not isinstance(name, str) or not name.strip():
        raise TopicError(f"invalid topic name {name!r}")
    name = name.strip()
    resolved = name if name.startswith("/") else "/" + name
    from rclpy.validate_full_topic_name import validate_full_topic_name
    try:
        validate_full_topic_name(resolved)
    except Exception as exc:
        raise TopicError(f"illegal ROS name '{name}': {exc}") from None
    return resolved


def _stamp() -> tuple:
    now = conversion._types.now()
    return (now.sec, now.nanosec)


def subscription_qos(topic: str) -> QoSProfile:
    """The QoS that hears every publisher of `topic` now in the graph (see the module's text)."""
    infos = node().get_publishers_info_by_topic(topic)
    reliable = not infos or any(i.qos_profile.reliability != ReliabilityPolicy.BEST_EFFORT for i in infos)
    latched = any(i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL for i in infos)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                      reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)


class SharedSubscriber(shared.SharedSubscriber):
    def __init__(self, topic: str, type_name: str, msg_cls: type) -> None:
        super().__init__(topic, type_name, msg_cls)
        qos = subscription_qos(topic)
        self._latching = qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
        self.sub = node().create_subscription(msg_cls, topic, self._callback, qos, callback_group=_rt.group)

    def _callback(self, msg: Any, info: Any) -> None:
        gid = info.get("publisher_gid") if isinstance(info, dict) else None
        publisher = bytes(gid["data"]).hex() if isinstance(gid, dict) and "data" in gid else str(gid)
        self.deliver(SharedMessage(self.topic, msg, _stamp()), publisher, self._latching)

    def unregister(self) -> None:
        node().destroy_subscription(self.sub)


class TopicHub(shared.TopicHub):
    subscriber_class = SharedSubscriber
    topic_types = staticmethod(topic_types)


class SharedPublisher:
    def __init__(self, topic: str, type_name: str, msg_cls: type, latch: bool, queue_size: int,
                 replay_window: float = 0.0, replay_max: int = 0) -> None:
        # DDS matches a late subscriber by itself; the replay window of ROS 1 (plumbing_ros1) is not needed.
        self.topic, self.type_name, self.msg_cls, self.latch = topic, type_name, msg_cls, latch
        self.clients: set = set()
        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=max(1, min(queue_size, 1000)),
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL if latch else DurabilityPolicy.VOLATILE)
        self.pub = node().create_publisher(msg_cls, topic, qos)

    def publish(self, msg: Any) -> None:
        self.pub.publish(msg)

    def unregister(self) -> None:
        node().destroy_publisher(self.pub)


class PublisherRegistry(shared.PublisherRegistry):
    publisher_class = SharedPublisher


def service_types() -> Dict[str, str]:
    return {name: _short(types[0]) for name, types in node().get_service_names_and_types() if types}


def call_service(name: str, args: Any, timeout: float = 30.0) -> tuple:
    """Blocking call of a ROS 2 service by name; returns (service type, response message)."""
    type_name = service_types().get(name)
    if not type_name:
        raise ServiceCallError(f"service {name} does not exist")
    srv_cls = conversion.get_service_class(type_name)
    request = conversion.args_to_request(conversion.request_class(srv_cls), args)
    client = _service_client(name, srv_cls)
    if not client.wait_for_service(timeout_sec=2.0):
        raise ServiceCallError(f"service {name} is not reachable")
    try:  # the first call to a new server may be sent twice: see cell_nodes.wiring.ros2.call
        return type_name, ros2_call(node(), client, name, request, timeout)
    except ServiceError as exc:
        raise ServiceCallError(str(exc)) from None


_service_clients: Dict[tuple, Any] = {}


def _service_client(name: str, srv_cls: type) -> Any:
    """One client per service and type for the server's life (rclpy clients are safe to share between threads): a
    client made per call is a new pair of DDS endpoints each time, each to be matched before it can be answered."""
    with _clients_lock:
        client = _service_clients.get((name, srv_cls))
        if client is None:
            client = _service_clients[(name, srv_cls)] = node().create_client(srv_cls, name, callback_group=_rt.group)
        return client


def serve(name: str, srv_cls: type, handler: Callable[[Any], Any]) -> Callable[[str], None]:
    """Offer a ROS 2 service answered by `handler`. ROS 2 services have no error reply: a failure
    (ServiceFailure) is logged and the caller gets a default response, as rosbridge_suite's ROS 2 server does."""
    response_cls = conversion.response_class(srv_cls)

    def answer(request: Any, done: Future) -> None:
        try:
            done.set_result(handler(request))
        except ServiceFailure as exc:
            log.warning("service %s failed: %s", name, exc)
            done.set_result(response_cls())
        except Exception:  # never leave the caller without an answer
            log.exception("service %s failed", name)
            done.set_result(response_cls())

    async def callback(request: Any, _response: Any) -> Any:
        done = Future(executor=_rt.executor)
        # A done callback makes set_result (from the handler's thread) schedule a task on the executor, which wakes
        # it: without one the awaiting callback would resume only at the executor's next event.
        done.add_done_callback(lambda _f: None)
        threading.Thread(target=answer, args=(request, done), name=f"serve {name}", daemon=True).start()
        return await done

    service = node().create_service(srv_cls, name, callback, callback_group=_rt.group)
    return lambda _reason: node().destroy_service(service)


def other_providers(name: str) -> List[str]:
    """Nodes other than this one serving `name`."""
    me = node()
    own = (me.get_name(), me.get_namespace())
    found = []
    for node_name, namespace in me.get_node_names_and_namespaces():
        if (node_name, namespace) == own:
            continue
        try:
            services = me.get_service_names_and_types_by_node(node_name, namespace)
        except Exception:  # the node left meanwhile
            continue
        if any(s == name for s, _ in services):
            found.append(namespace.rstrip("/") + "/" + node_name)
    return found


class _GoalHandle:
    """What cancel_action_goal holds of a running goal: cancel() asks the server to cancel it."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._handle: Any = None
        self._cancel_wanted = False

    def attach(self, handle: Any) -> None:
        with self._lock:
            self._handle = handle
            wanted = self._cancel_wanted
        if wanted:
            handle.cancel_goal_async()

    def cancel(self) -> None:
        with self._lock:
            self._cancel_wanted = True
            handle = self._handle
        if handle is not None:
            handle.cancel_goal_async()


def _wait(future: Any, timeout: Optional[float], what: str) -> Any:
    done = threading.Event()
    future.add_done_callback(lambda _f: done.set())
    if not done.wait(timeout):
        raise ActionGoalError(f"{what}: no answer within {timeout:g} s")
    if future.exception() is not None:
        raise ActionGoalError(f"{what}: {future.exception()}")
    return future.result()


def send_action_goal(name: str, type_name: str, args: Any, on_feedback: Callable[[Any], None],
                     on_handle: Callable[[Any], None], server_timeout: float = 5.0) -> tuple:
    """Send a goal to the ROS 2 action server `name` and wait for its end; returns (GoalStatus, result message).
    `on_handle` gets the goal's cancel handle at once (a cancel before the server accepted it applies on accept)."""
    try:
        action_cls = conversion._types.load_action(conversion.normalize_type(type_name))
    except ValueError as exc:
        raise ActionGoalError(str(exc)) from None
    if action_cls is None:
        raise ActionGoalError(f"unknown action type '{type_name}'")
    goal = conversion.dict_to_msg(action_cls.Goal, args, path="args")
    handle = _GoalHandle()
    on_handle(handle)
    client = _action_client(name, action_cls)
    if not client.wait_for_server(timeout_sec=server_timeout):
        raise ActionGoalError(f"action server {name} is not available")
    # A new client's feedback subscription may not be matched yet when the server sends its first feedback
    # (volatile QoS drops it): wait, briefly, until the graph shows the two ends of the feedback topic.
    feedback_topic = f"{name.rstrip('/')}/_action/feedback"
    deadline = time.monotonic() + 1.0
    while node().count_publishers(feedback_topic) == 0 and time.monotonic() < deadline:
        threading.Event().wait(0.01)
    goal_handle = _wait(client.send_goal_async(goal, feedback_callback=lambda fb: on_feedback(fb.feedback)),
                        30.0, f"goal to {name}")
    if not goal_handle.accepted:
        raise ActionGoalError(f"goal to {name} was rejected")
    handle.attach(goal_handle)
    response = _wait(goal_handle.get_result_async(), None, f"result of {name}")
    return response.status, response.result


_action_clients: Dict[tuple, Any] = {}
_clients_lock = threading.Lock()


def _action_client(name: str, action_cls: type) -> Any:
    """One action client per action and type for the server's life: a client made per goal is a new DDS reader
    each time, which the server's first feedback of that goal may not reach."""
    from rclpy.action import ActionClient
    with _clients_lock:
        client = _action_clients.get((name, action_cls))
        if client is None:
            client = _action_clients[(name, action_cls)] = ActionClient(node(), action_cls, name,
                                                                        callback_group=_rt.group)
        return client
