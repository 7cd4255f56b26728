"""rosapi under a stream of calls leaves nothing behind per call.

A master proxy per service thread (and rosservice's proxy per call) left a socket per call to the garbage
collector; tracemalloc showed those sockets' buffers and texts retained, ~250 B per call: rosapi's steady RSS growth
in the soak. rosapi runs with every ResourceWarning shown (conftest.py), so a socket left behind shows in its log.
"""
from __future__ import annotations

import subprocess
from pathlib import Path


def test_rosapi_calls_leave_no_socket_to_the_garbage_collector(ros_node: str, rosapi: subprocess.Popen) -> None:
    import rospy
    from rosapi import srv

    calls = [("/rosapi/topics", srv.Topics, ()), ("/rosapi/services", srv.Services, ()),
             ("/rosapi/nodes", srv.Nodes, ()), ("/rosapi/service_type", srv.ServiceType, ("/rosapi/topics",)),
             ("/rosapi/node_details", srv.NodeDetails, ("/rosapi",)),
             ("/rosapi/publishers", srv.Publishers, ("/rosout",))]
    for i in range(120):
        name, cls, args = calls[i % len(calls)]
        assert rospy.ServiceProxy(name, cls)(*args) is not None  # a new connection each time: a new thread there
    assert "/rosapi/topics" in rospy.ServiceProxy("/rosapi/services", srv.Services)().services
    log = Path(rosapi.stderr_path).read_text()  # type: ignore[attr-defined]
    assert log.count("unclosed") == 0, log[-2000:]
