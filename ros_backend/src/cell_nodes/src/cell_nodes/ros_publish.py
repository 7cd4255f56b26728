"""The rospy side shared by the nodes: publishing while the node stops.

rospy closes every topic in its shutdown sequence, before ``rospy.is_shutdown()`` may say so, while timers,
driver threads and action callbacks still publish. That "publish() to a closed topic" is the node stopping,
not an error; anything else still raises.
"""
from __future__ import annotations

import rospy


def stopping(error: rospy.ROSException) -> bool:
    """Whether ``error`` from ``publish()`` only means the node is shutting down."""
    return rospy.is_shutdown() or rospy.core.is_shutdown_requested() or "closed topic" in str(error)


def publish(pub: rospy.Publisher, msg: object) -> bool:
    """Publish ``msg``; False (and no traceback) when the topic was closed by the node's shutdown."""
    try:
        pub.publish(msg)
        return True
    except rospy.ROSException as e:
        if stopping(e):
            return False
        raise
