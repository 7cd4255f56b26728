"""The rosbridge_server node on ROS 2: node parameters (`--ros-args -p port:=9090 ...`), rclpy, then server.run.

The parameters are the ROS 1 node's private ones under the same names (port, address, max_message_size, ...).
"""
from __future__ import annotations

import os
from typing import Any, List, Optional

import rclpy

from . import plumbing_ros2
from .protocol import BridgeConfig
from .server import log_to_stderr, run


def main(argv: Optional[List[str]] = None) -> None:
    rclpy.init(args=argv)
    node = plumbing_ros2.start("rosbridge_websocket")
    log_to_stderr()

    def param(name: str, default: Any) -> Any:
        return type(default)(node.declare_parameter(name, default).value)

    port = param("port", int(os.environ.get("ROSBRIDGE_PORT", "9090")))
    address = param("address", "127.0.0.1")
    cfg = BridgeConfig(**{name: param(name, getattr(BridgeConfig, name)) for name in BridgeConfig.TUNABLE})
    try:
        run(cfg, port, address, lambda text: node.get_logger().info(text))
    finally:
        plumbing_ros2.stop()
