"""Our diagnostic_msgs must be the public package field for field: every real driver publishes these on /diagnostics,
and rospy only connects publisher and subscriber when their md5sums agree. The expected values are those
ros/common_msgs' diagnostic_msgs (ROS 1) carries in its generated code."""
from __future__ import annotations

import pytest

PUBLISHED = {
    "KeyValue": "cf57fdc6617a881a88c16e768132149c",
    "DiagnosticStatus": "d0ce08bc6e5ba34c7754f563a9cabaf1",
    "DiagnosticArray": "60810da900de1dd6ddd437c3503511da",
}


@pytest.mark.parametrize("name", sorted(PUBLISHED))
def test_md5sum_matches_the_published_package(name: str) -> None:
    import diagnostic_msgs.msg as m
    cls = getattr(m, name)
    assert cls._type == f"diagnostic_msgs/{name}"
    assert cls._md5sum == PUBLISHED[name], f"diagnostic_msgs/{name} differs from the public definition"


def test_levels_are_the_public_ones() -> None:
    from diagnostic_msgs.msg import DiagnosticStatus as S
    assert (S.OK, S.WARN, S.ERROR, S.STALE) == (0, 1, 2, 3)
