"""Publishing a node's diagnostics on /diagnostics (diagnostic_msgs/DiagnosticArray), the way real drivers do.

A node on cell_nodes.wiring passes its wiring (`publisher(ros)`) and the stamp (`report(pub, statuses, stamp)`);
the rospy nodes not yet moved to the wiring call both without (rospy is then imported here).
"""
from __future__ import annotations

from typing import Any, Iterable, Optional

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from .diagnostics import DiagStatus

TOPIC = "/diagnostics"
# The level is a `byte`: an int on ROS 1, a bytes object of length 1 (octet) on ROS 2.
_LEVEL = (lambda level: bytes([level])) if isinstance(DiagnosticStatus.OK, bytes) else int


def level_of(status: DiagnosticStatus) -> int:
    """A status's level as the int every reader compares (either generation)."""
    level = status.level
    return level[0] if isinstance(level, (bytes, bytearray)) else int(level)


def publisher(ros: Any = None) -> Any:
    if ros is not None:
        return ros.publisher(TOPIC, DiagnosticArray, queue_size=10)
    import rospy
    return rospy.Publisher(TOPIC, DiagnosticArray, queue_size=10)


def to_msg(statuses: Iterable[DiagStatus], stamp: Optional[Any] = None) -> DiagnosticArray:
    msg = DiagnosticArray()
    if stamp is None:
        import rospy
        stamp = rospy.Time.now()
    msg.header.stamp = stamp
    msg.status = [DiagnosticStatus(level=_LEVEL(s.level), name=s.name, message=s.message, hardware_id=s.hardware_id,
                                   values=[KeyValue(key=k, value=v) for k, v in s.values]) for s in statuses]
    return msg


def report(pub: Any, statuses: Iterable[DiagStatus], stamp: Optional[Any] = None) -> None:
    if stamp is None:  # a rospy publisher
        from .ros_publish import publish
        publish(pub, to_msg(statuses))
    else:  # a wiring publisher (its publish() already knows a stopping node)
        pub.publish(to_msg(statuses, stamp))
