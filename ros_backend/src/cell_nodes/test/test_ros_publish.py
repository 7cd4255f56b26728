"""Publishing while a node stops: rospy closes the topics before is_shutdown() says so (a CI traceback).

rospy's publish() needs an initialised node, one per process; a stand-in raises what rospy's raises.
"""
import pytest
import rospy

from cell_nodes.ros_publish import publish


class Pub:
    def __init__(self, error: str = "") -> None:
        self.error, self.sent = error, []

    def publish(self, msg: object) -> None:
        if self.error:
            raise rospy.ROSException(self.error)
        self.sent.append(msg)


def test_a_topic_closed_by_the_shutdown_is_not_an_error_but_other_failures_still_raise() -> None:
    ok = Pub()
    assert publish(ok, "a") is True and ok.sent == ["a"]
    assert publish(Pub("publish() to a closed topic"), "late") is False  # rospy/topics.py's own words
    with pytest.raises(rospy.ROSException, match="unregistered"):
        publish(Pub("publish() to an unregistered() handle"), "after unregister")
