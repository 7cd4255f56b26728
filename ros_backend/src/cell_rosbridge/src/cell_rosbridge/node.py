"""The rosbridge_server node on ROS 1: private parameters, rospy init, then server.run."""
from __future__ import annotations

import os
from typing import Any

import rospy

from .plumbing_ros1 import publish_without_yield
from .protocol import BridgeConfig
from .server import build_context, log_to_stderr, run

__all__ = ["build_context", "main"]


def _param(name: str, default: Any) -> Any:
    value = rospy.get_param(name, default)
    return type(default)(value) if default is not None else value


def main(argv: Any = None) -> None:
    # Our own signal handling: rospy's handler runs hooks inside the signal frame, where tornado's
    # add_callback does not wake the loop (it thinks it is on the loop thread), so SIGINT would hang.
    rospy.init_node("rosbridge_websocket", argv=argv, disable_signals=True)
    publish_without_yield()  # publishes run on the loop thread (see there)
    # rospy already configured the root logger (ROS log file); also show our own lines on stderr.
    log_to_stderr()
    port = _param("~port", int(os.environ.get("ROSBRIDGE_PORT", "9090")))
    address = _param("~address", "127.0.0.1")
    cfg = BridgeConfig(**{name: _param(f"~{name}", getattr(BridgeConfig, name)) for name in BridgeConfig.TUNABLE})
    try:
        run(cfg, port, address, lambda text: rospy.loginfo(text))
    finally:
        if not rospy.is_shutdown():
            rospy.signal_shutdown("rosbridge stopped")
