"""Publishing a node's diagnostics on /diagnostics (diagnostic_msgs/DiagnosticArray), the way real drivers do."""
from __future__ import annotations

from typing import Iterable

import rospy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from .diagnostics import DiagStatus
from .ros_publish import publish

TOPIC = "/diagnostics"


def publisher() -> rospy.Publisher:
    return rospy.Publisher(TOPIC, DiagnosticArray, queue_size=10)


def to_msg(statuses: Iterable[DiagStatus]) -> DiagnosticArray:
    msg = DiagnosticArray()
    msg.header.stamp = rospy.Time.now()
    msg.status = [DiagnosticStatus(level=s.level, name=s.name, message=s.message, hardware_id=s.hardware_id,
                                   values=[KeyValue(key=k, value=v) for k, v in s.values]) for s in statuses]
    return msg


def report(pub: rospy.Publisher, statuses: Iterable[DiagStatus]) -> None:
    publish(pub, to_msg(statuses))
