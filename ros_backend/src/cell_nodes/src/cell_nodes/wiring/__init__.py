"""The nodes' ROS wiring, written once against a small interface of our own (api.Wiring) with a rospy and an rclpy
implementation: a node script asks `connect(name)` for its generation's wiring (ROS_VERSION, as both generations'
setup scripts export it; 1 if unset) and hands it to its logic. Message and service classes are imported by
package name (`from cell_msgs.msg import ...`), the same on both generations.
"""
from __future__ import annotations

import os
from typing import Any, List, Optional

from .api import Handle, Publisher, ServiceClient, ServiceError, Wiring

ROS_VERSION: int = 2 if os.environ.get("ROS_VERSION", "1").strip() == "2" else 1

__all__ = ["Handle", "Publisher", "ServiceClient", "ServiceError", "Wiring", "ROS_VERSION", "connect"]


def connect(name: str, argv: Optional[List[str]] = None, anonymous: bool = False, **options: Any) -> Wiring:
    """This process's node on its generation's graph. `argv`: the node's command line (remappings, parameters:
    ROS 1 `_name:=value`, ROS 2 `--ros-args -p name:=value`)."""
    if ROS_VERSION == 2:
        from .ros2 import Ros2Wiring
        return Ros2Wiring(name, argv, anonymous, **options)
    from .ros1 import Ros1Wiring
    return Ros1Wiring(name, argv, anonymous, **options)
