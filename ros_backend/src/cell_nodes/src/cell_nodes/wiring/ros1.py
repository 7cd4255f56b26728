"""The nodes' wiring on ROS 1 (rospy)."""
from __future__ import annotations

from typing import Any, Callable, List, Optional

import rosgraph
import rospy

from .. import ros_publish
from .api import Closer, ServiceError


class _Publisher:
    def __init__(self, pub: rospy.Publisher) -> None:
        self.pub = pub

    def publish(self, msg: Any) -> bool:
        return ros_publish.publish(self.pub, msg)

    def subscriber_count(self) -> int:
        return self.pub.get_num_connections()

    def close(self) -> None:
        self.pub.unregister()


class _Client:
    def __init__(self, name: str, srv_cls: type) -> None:
        self.name, self.srv_cls = name, srv_cls
        self.proxy = rospy.ServiceProxy(name, srv_cls)

    def wait(self, timeout: float) -> bool:
        try:
            rospy.wait_for_service(self.name, timeout=timeout)
            return True
        except rospy.ROSException:
            return False

    def __call__(self, request: Any = None, timeout: float = 10.0, **fields: Any) -> Any:
        if request is None:
            request = self.srv_cls._request_class(**fields)
        if not self.wait(timeout):
            raise ServiceError(f"service {self.name} is not available")
        try:
            return self.proxy.call(request)
        except (rospy.ServiceException, rospy.ROSException) as exc:
            raise ServiceError(f"service {self.name} failed: {exc}") from exc

    def close(self) -> None:
        self.proxy.close()


class Ros1Wiring:
    ros_version = 1

    def __init__(self, name: str, argv: Optional[List[str]] = None, anonymous: bool = False,
                 disable_signals: bool = False) -> None:
        if not rospy.core.is_initialized():
            rospy.init_node(name, argv=argv, anonymous=anonymous, disable_signals=disable_signals)
        self.name = rospy.get_name()

    def param(self, name: str, default: Any) -> Any:
        return rospy.get_param("~" + name, default)

    def publisher(self, topic: str, msg_cls: type, latch: bool = False, queue_size: int = 10) -> _Publisher:
        return _Publisher(rospy.Publisher(topic, msg_cls, latch=latch, queue_size=queue_size, tcp_nodelay=True))

    def subscribe(self, topic: str, msg_cls: type, callback: Callable[[Any, str], None], queue_size: int = 10,
                  latched: bool = False, newest_only: bool = False) -> Closer:
        def on_message(msg: Any) -> None:
            header = getattr(msg, "_connection_header", None) or {}
            callback(msg, str(header.get("callerid", "")))

        if newest_only:  # rospy reads at most buff_size at once: a frame bigger than it would arrive late
            sub = rospy.Subscriber(topic, msg_cls, on_message, queue_size=1, buff_size=1 << 25)
        else:
            sub = rospy.Subscriber(topic, msg_cls, on_message, queue_size=queue_size)
        return Closer(sub.unregister)

    def subscribers(self, topic: str) -> list[str]:
        _, subs, _ = rosgraph.Master(self.name).getSystemState()
        return sorted(next((nodes for name, nodes in subs if name == topic), []))

    def service(self, name: str, srv_cls: type, handler: Callable[[Any], Any]) -> Closer:
        svc = rospy.Service(name, srv_cls, handler)
        return Closer(lambda: svc.shutdown("closed"))

    def client(self, name: str, srv_cls: type) -> _Client:
        return _Client(name, srv_cls)

    def request(self, srv_cls: type, **fields: Any) -> Any:
        return srv_cls._request_class(**fields)

    def response(self, srv_cls: type, **fields: Any) -> Any:
        return srv_cls._response_class(**fields)

    def timer(self, period: float, callback: Callable[[], None]) -> Closer:
        timer = rospy.Timer(rospy.Duration.from_sec(period), lambda _event: callback())
        return Closer(timer.shutdown)

    def now(self) -> float:
        return rospy.get_time()

    def stamp(self, seconds: float) -> Any:
        return rospy.Time.from_sec(seconds)

    def seconds(self, stamp: Any) -> float:
        return stamp.to_sec()

    def info(self, text: str, *args: Any) -> None:
        rospy.loginfo(text, *args)

    def warn(self, text: str, *args: Any) -> None:
        rospy.logwarn(text, *args)

    def error(self, text: str, *args: Any) -> None:
        rospy.logerr(text, *args)

    def ok(self) -> bool:
        return not rospy.is_shutdown()

    def sleep(self, seconds: float) -> bool:
        try:
            rospy.sleep(seconds)
        except rospy.ROSInterruptException:
            return False
        return self.ok()

    def wait_for_message(self, topic: str, msg_cls: type, timeout: float) -> Any:
        try:
            return rospy.wait_for_message(topic, msg_cls, timeout=timeout)
        except rospy.ROSException:  # timed out, or shutting down
            return None

    def spin(self) -> None:
        rospy.spin()

    def shutdown(self, reason: str = "") -> None:
        rospy.signal_shutdown(reason or "shutdown")
