"""The ros_control backend's rospy layer (RosTransport) against a real actionlib server on a roscore: a goal's end
reaches the arm however fast the controller answers."""
from __future__ import annotations

from typing import Iterator

import actionlib
import pytest
from actionlib.action_client import CommState
from actionlib_msgs.msg import GoalStatus
from control_msgs.msg import FollowJointTrajectoryAction, FollowJointTrajectoryResult

from conftest import wait_for
from nodes_helpers import client_node
from cell_nodes.manual.config import RosControlSpec
from cell_nodes.manual.ros_control.transport import RosTransport
from cell_nodes.manual.ros_control.trajectory import TrajectoryPoint

SPEC = RosControlSpec(joint_states="/transport_test/joint_states", controller="/transport_test/ctrl",
                      base_link="base", tip_link="tip")
JOINTS = ["a", "b"]


class InstantController:
    """A trajectory controller that answers each goal at once (a move already at its target), or aborts it."""

    def __init__(self) -> None:
        self.abort = False
        self.server = actionlib.ActionServer(SPEC.action, FollowJointTrajectoryAction, self._on_goal, auto_start=False)
        self.server.start()

    def _on_goal(self, gh) -> None:
        gh.set_accepted()
        if self.abort:
            gh.set_aborted(FollowJointTrajectoryResult(error_code=FollowJointTrajectoryResult.PATH_TOLERANCE_VIOLATED,
                                                       error_string="blocked"))
        else:
            gh.set_succeeded(FollowJointTrajectoryResult(error_code=FollowJointTrajectoryResult.SUCCESSFUL))


@pytest.fixture(scope="module")
def rig(roscore: str) -> Iterator[tuple[InstantController, RosTransport]]:
    client_node("transport_test_client")
    controller = InstantController()
    transport = RosTransport(SPEC, joints=JOINTS)
    wait_for(transport.controller_ready, 10, what="the action server's status")
    yield controller, transport
    transport.close()
    controller.server.stop()


def _send(transport: RosTransport) -> list[tuple[int, int, str]]:
    ended: list[tuple[int, int, str]] = []
    transport.send_goal(JOINTS, [TrajectoryPoint([0.0, 0.0], [0.0, 0.0], 0.1)], 0.1, 1.0,
                        lambda state, code, text: ended.append((state, code, text)))
    return ended


def test_a_result_that_arrives_before_send_goal_returns_still_ends_the_goal(
        rig: tuple[InstantController, RosTransport], monkeypatch: pytest.MonkeyPatch) -> None:
    # The race as a loaded host plays it: the goal is published, and the sending thread gets the CPU back only after
    # the controller's result has been taken in (all of the goal's transitions happen before send_goal returns).
    controller, transport = rig
    manager = transport._client.manager
    publish = manager.send_goal_fn

    def publish_then_stall(action_goal) -> None:
        publish(action_goal)
        machine = next(m for m in (r() for r in manager.statuses) if m is not None
                       and m.action_goal.goal_id.id == action_goal.goal_id.id)
        wait_for(lambda: machine.state == CommState.DONE, 10, 0.005, "the goal's result taken in")

    monkeypatch.setattr(manager, "send_goal_fn", publish_then_stall)
    ended = _send(transport)
    assert ended == [(GoalStatus.SUCCEEDED, 0, "")]


def test_each_goal_ends_once_with_its_own_state_and_reason(rig: tuple[InstantController, RosTransport]) -> None:
    controller, transport = rig
    ok = _send(transport)
    wait_for(lambda: bool(ok), 10, 0.005, "the first goal's end")
    controller.abort = True
    try:
        failed = _send(transport)
        wait_for(lambda: bool(failed), 10, 0.005, "the second goal's end")
    finally:
        controller.abort = False
    assert ok == [(GoalStatus.SUCCEEDED, 0, "")]
    assert failed == [(GoalStatus.ABORTED, FollowJointTrajectoryResult.PATH_TOLERANCE_VIOLATED, "blocked")]
