"""Our control_msgs subset must be the public package field for field: a real controller's action server and our
client only talk when their md5sums agree. The expected values are those ros-controls/control_msgs (ROS 1, 1.5.x)
publishes (its generated code carries them)."""
from __future__ import annotations

import pytest

PUBLISHED = {
    "JointTolerance": "f544fe9c16cf04547e135dd6063ff5be",
    "FollowJointTrajectoryAction": "bc4f9b743838566551c0390c65f1a248",
    "FollowJointTrajectoryActionGoal": "cff5c1d533bf2f82dd0138d57f4304bb",
    "FollowJointTrajectoryGoal": "69636787b6ecbde4d61d711979bc7ecb",
    "FollowJointTrajectoryResult": "493383b18409bfb604b4e26c676401d2",
    "FollowJointTrajectoryFeedback": "10817c60c2486ef6b33e97dcd87f4474",
    "FollowJointTrajectoryActionResult": "c4fb3b000dc9da4fd99699380efcc5d9",
    "FollowJointTrajectoryActionFeedback": "d8920dc4eae9fc107e00999cce4be641",
}


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_md5sum_matches_the_published_package(name: str) -> None:
    import control_msgs.msg as m
    cls = getattr(m, name)
    assert cls._type == f"control_msgs/{name}"
    assert cls._md5sum == PUBLISHED[name], f"control_msgs/{name} differs from the public definition"


def test_result_codes_are_the_public_ones() -> None:
    from control_msgs.msg import FollowJointTrajectoryResult as R
    assert (R.SUCCESSFUL, R.INVALID_GOAL, R.INVALID_JOINTS, R.OLD_HEADER_TIMESTAMP, R.PATH_TOLERANCE_VIOLATED,
            R.GOAL_TOLERANCE_VIOLATED) == (0, -1, -2, -3, -4, -5)
